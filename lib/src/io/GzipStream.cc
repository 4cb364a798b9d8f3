// GzipStream.cc - pieces deflated in parallel, joined into one gzip member (GzipStream.h).
#include "io/GzipStream.h"

#include <fluidsurf/Error.h>

#include "io/StreamFile.h"

#include <tbb/task_arena.h>
#include <tbb/task_group.h>

#include <zlib.h>

#include <algorithm>
#include <atomic>

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

struct GzipStream::Piece
{
    std::string in, dictionary, out;
    uint32_t crc = 0;
    std::atomic<bool> done{false};
    tbb::task_group task;
};

GzipStream::GzipStream(StreamFile& out, int level)
    : mOut(out), mLevel(level),
      mMaxFlight(size_t(std::max(2, 2 * tbb::this_task_arena::max_concurrency())))
{
    // as zlib writes it: no name, no time, the extra flags of the level, Unix
    const char extra = level == 9 ? 2 : (level < 2 ? 4 : 0);
    const char head[10] = {'\x1f', '\x8b', 8, 0, 0, 0, 0, 0, extra, 3};
    mOut.write(head, sizeof head);
    mFilling.reserve(kPiece);
}

GzipStream::~GzipStream()
{
    for (const std::unique_ptr<Piece>& piece : mFlight) {
        try {
            piece->task.wait();
        } catch (...) {
        }
    }
}

void GzipStream::write(const void* data, size_t size)
{
    const char* p = static_cast<const char*>(data);
    while (size > 0) {
        if (mFilling.size() == kPiece) submit(false); // full, and more comes: not the last
        const size_t take = std::min(size, kPiece - mFilling.size());
        mFilling.append(p, take);
        p += take;
        size -= take;
    }
}

void GzipStream::submit(bool last)
{
    auto piece = std::make_unique<Piece>();
    piece->in.swap(mFilling);
    piece->dictionary.swap(mWindow);
    const std::string& in = piece->in;
    mWindow.assign(in, in.size() - std::min(in.size(), kWindow), std::string::npos);
    mFilling.reserve(kPiece);
    Piece& p = *piece;
    const int level = mLevel;
    p.task.run([&p, level, last] {
        p.out = deflatePiece(p.in, p.dictionary.data(), p.dictionary.size(), level, last);
        p.crc = uint32_t(crc32(0, reinterpret_cast<const Bytef*>(p.in.data()), uInt(p.in.size())));
        p.done.store(true, std::memory_order_release);
    });
    mFlight.push_back(std::move(piece));
    // what is done goes out; more than mMaxFlight in flight waits for the oldest
    while (!mFlight.empty() && retire(mFlight.size() > mMaxFlight)) {
    }
}

bool GzipStream::retire(bool wait)
{
    Piece& piece = *mFlight.front();
    if (!wait && !piece.done.load(std::memory_order_acquire)) return false;
    piece.task.wait(); // (rethrows the task's error)
    mOut.write(piece.out);
    mCrc = uint32_t(crc32_combine(mCrc, piece.crc, z_off_t(piece.in.size())));
    mLength += piece.in.size();
    mFlight.pop_front();
    return true;
}

void GzipStream::finish()
{
    if (mFinished) return;
    mFinished = true;
    submit(true);
    while (!mFlight.empty())
        retire(true);
    char trailer[8];
    for (int b = 0; b < 4; ++b) {
        trailer[b] = char(mCrc >> (8 * b));
        trailer[4 + b] = char(uint32_t(mLength) >> (8 * b));
    }
    mOut.write(trailer, sizeof trailer);
}

} // namespace io
} // namespace fluidsurf
