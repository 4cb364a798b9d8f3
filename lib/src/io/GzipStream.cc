// GzipStream.cc - pieces deflated in parallel, joined into one gzip member (GzipStream.h).
#include "io/GzipStream.h"

#include <fluidsurf/Error.h>

#include "io/StreamFile.h"

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <zlib.h>

#include <algorithm>

namespace fluidsurf {
namespace io {

namespace {
constexpr size_t kWindow = size_t(1) << 15; // deflate's reach back

/// One piece as raw deflate: primed with dictionary, ended by a sync flush (a byte boundary,
/// so that the next piece's bytes follow on) or, for the last, by the final block.
std::string deflatePiece(const std::string& piece, const char* dictionary, size_t dictionarySize,
                         int level, bool last)
{
    z_stream zs{};
    if (deflateInit2(&zs, level, Z_DEFLATED, -15, 8, Z_DEFAULT_STRATEGY) != Z_OK)
        throw OutputError("zlib deflate init failed");
    struct End
    {
        z_stream* zs;
        ~End() { deflateEnd(zs); }
    } end{&zs};
    if (dictionarySize > 0 && deflateSetDictionary(&zs, reinterpret_cast<const Bytef*>(dictionary),
                                                   uInt(dictionarySize)) != Z_OK)
        throw OutputError("zlib deflate dictionary failed");
    std::string out(deflateBound(&zs, uLong(piece.size())) + 64, '\0');
    zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(piece.data()));
    zs.avail_in = uInt(piece.size()); // at most kPiece
    const int flush = last ? Z_FINISH : Z_SYNC_FLUSH;
    for (;;) {
        zs.next_out = reinterpret_cast<Bytef*>(&out[zs.total_out]);
        zs.avail_out = uInt(out.size() - zs.total_out);
        const int ret = deflate(&zs, flush);
        if (ret == Z_STREAM_ERROR) throw OutputError("gzip compression failed");
        // a flush is complete when deflate leaves output room unused
        if (last ? ret == Z_STREAM_END : (zs.avail_in == 0 && zs.avail_out > 0)) break;
        out.resize(out.size() * 2);
    }
    out.resize(zs.total_out);
    return out;
}
} // namespace

GzipStream::GzipStream(StreamFile& out, int level)
    : mOut(out), mLevel(level),
      mBatchPieces(size_t(std::max(2, 2 * tbb::this_task_arena::max_concurrency())))
{
    // as zlib writes it: no name, no time, the extra flags of the level, Unix
    const char extra = level == 9 ? 2 : (level < 2 ? 4 : 0);
    const char head[10] = {'\x1f', '\x8b', 8, 0, 0, 0, 0, 0, extra, 3};
    mOut.write(head, sizeof head);
    mBatch.emplace_back();
    mBatch.back().reserve(kPiece);
}

void GzipStream::write(const void* data, size_t size)
{
    const char* p = static_cast<const char*>(data);
    while (size > 0) {
        if (mBatch.back().size() == kPiece) { // full, and more comes: not the last piece
            if (mBatch.size() == mBatchPieces) compressBatch(false);
            mBatch.emplace_back();
            mBatch.back().reserve(kPiece);
        }
        std::string& piece = mBatch.back();
        const size_t take = std::min(size, kPiece - piece.size());
        piece.append(p, take);
        p += take;
        size -= take;
    }
}

void GzipStream::compressBatch(bool last)
{
    const size_t n = mBatch.size();
    std::vector<std::string> deflated(n);
    std::vector<uint32_t> crcs(n);
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
        const std::string& before = i == 0 ? mWindow : mBatch[i - 1];
        const size_t reach = std::min(before.size(), kWindow);
        deflated[i] = deflatePiece(mBatch[i], before.data() + before.size() - reach, reach, mLevel,
                                   last && i + 1 == n);
        crcs[i] = uint32_t(
            crc32(0, reinterpret_cast<const Bytef*>(mBatch[i].data()), uInt(mBatch[i].size())));
    });
    for (size_t i = 0; i < n; ++i) {
        mOut.write(deflated[i]);
        mCrc = uint32_t(crc32_combine(mCrc, crcs[i], z_off_t(mBatch[i].size())));
        mLength += mBatch[i].size();
    }
    const std::string& tail = mBatch.back();
    mWindow.assign(tail, tail.size() - std::min(tail.size(), kWindow), std::string::npos);
    mBatch.clear();
}

void GzipStream::finish()
{
    if (mFinished) return;
    mFinished = true;
    compressBatch(true);
    char trailer[8];
    for (int b = 0; b < 4; ++b) {
        trailer[b] = char(mCrc >> (8 * b));
        trailer[4 + b] = char(uint32_t(mLength) >> (8 * b));
    }
    mOut.write(trailer, sizeof trailer);
}

} // namespace io
} // namespace fluidsurf
