// GzipStreamTest.cc - the parallel gzip writer of `.bgeo.gz`: zlib's own inflate (not our
// reader) must give back exactly what went in, from one gzip member, for any thread count.
#include "TestData.h"

#include "io/GzipStream.h"
#include "io/StreamFile.h"

#include <gtest/gtest.h>
#include <tbb/task_arena.h>
#include <zlib.h>

#include <random>
#include <string>

namespace fluidsurf {
namespace {

/// The file through `threads` threads, written in uneven slices (so that pieces are cut inside a
/// write and a write fills several pieces).
std::string gzipThroughStream(const std::string& data, int threads, const test::TempDir& dir)
{
    const std::string path = dir.path("s" + std::to_string(threads) + ".gz");
    tbb::task_arena(threads).execute([&] {
        io::StreamFile file(path);
        io::GzipStream out(file);
        const size_t slices[] = {1, 7, 100003, 3 << 20, 65536, 12345};
        for (size_t at = 0, k = 0; at < data.size(); ++k) {
            const size_t n = std::min(slices[k % 6], data.size() - at);
            out.write(data.data() + at, n);
            at += n;
        }
        out.finish();
        file.commit();
    });
    return test::readFileBytes(path);
}

/// zlib's inflate of one gzip member (its CRC and length checked by zlib); fails the test when
/// the member does not end exactly at the end of the file.
std::string inflateOneMember(const std::string& gz)
{
    z_stream zs{};
    EXPECT_EQ(inflateInit2(&zs, 15 + 16), Z_OK);
    zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(gz.data()));
    zs.avail_in = uInt(gz.size());
    std::string out;
    char buffer[1 << 16];
    int ret = Z_OK;
    while (ret == Z_OK) {
        zs.next_out = reinterpret_cast<Bytef*>(buffer);
        zs.avail_out = sizeof buffer;
        ret = inflate(&zs, Z_NO_FLUSH);
        out.append(buffer, sizeof buffer - zs.avail_out);
    }
    EXPECT_EQ(ret, Z_STREAM_END) << (zs.msg ? zs.msg : "");
    EXPECT_EQ(zs.avail_in, 0u) << "bytes after the first gzip member";
    inflateEnd(&zs);
    return out;
}

/// Particle-like data: float words with few distinct high bytes, and runs copied from up to
/// 40 KiB back (some across the pieces' ends, some beyond deflate's window).
std::string sampleData(size_t size, unsigned seed)
{
    std::mt19937 rng(seed);
    std::string s;
    s.reserve(size);
    while (s.size() < size) {
        if (s.size() > 50000 && rng() % 4 == 0) {
            const size_t back = 1 + rng() % 40000, n = std::min<size_t>(1 + rng() % 300, back);
            s.append(s, s.size() - back, n);
        } else {
            const uint32_t word = 0x3f800000u + (rng() % 4096) * 97;
            s.append(reinterpret_cast<const char*>(&word), 4);
        }
    }
    s.resize(size);
    return s;
}

TEST(GzipStream, ZlibInflatesExactlyWhatWentInForAnyThreadCount)
{
    const test::TempDir dir;
    // nine and a half pieces: with 2 threads a batch holds 4, so the dictionary crosses batches
    const std::string data = sampleData(9 * io::GzipStream::kPiece + 500001, 1);
    const std::string one = gzipThroughStream(data, 1, dir);
    EXPECT_EQ(inflateOneMember(one), data);
    EXPECT_EQ(one.substr(0, 4), std::string("\x1f\x8b\x08\x00", 4));
    EXPECT_EQ(gzipThroughStream(data, 2, dir), one);
    EXPECT_EQ(gzipThroughStream(data, 5, dir), one);
    // as small as one zlib stream of it, within 0.5% (the flushes cost a few bytes a piece)
    const std::string whole = test::gzipBytes(data);
    EXPECT_LT(double(one.size()), double(whole.size()) * 1.005 + 64);
}

TEST(GzipStream, EachPieceSeesTheWindowBeforeIt)
{
    // one random 30 KB block over and over: a piece primed with the 32 KiB before it finds
    // the block there, as one stream would; a piece on its own would store it again (7 times)
    std::mt19937 rng(7);
    std::string block(30000, '\0');
    for (char& c : block)
        c = char(rng());
    std::string data;
    while (data.size() < 8 * io::GzipStream::kPiece)
        data += block;
    const test::TempDir dir;
    const std::string gz = gzipThroughStream(data, 3, dir);
    EXPECT_EQ(inflateOneMember(gz), data);
    EXPECT_LT(gz.size(), test::gzipBytes(data).size() + block.size());
}

TEST(GzipStream, EmptyAndWholePieces)
{
    const test::TempDir dir;
    for (const size_t size : {size_t(0), size_t(1), io::GzipStream::kPiece,
                              2 * io::GzipStream::kPiece, 2 * io::GzipStream::kPiece + 1}) {
        const std::string data = sampleData(size, 3);
        const std::string gz = gzipThroughStream(data, 2, dir);
        EXPECT_EQ(inflateOneMember(gz), data) << size << " bytes";
        EXPECT_EQ(gzipThroughStream(data, 1, dir), gz) << size << " bytes";
    }
}

} // namespace
} // namespace fluidsurf
