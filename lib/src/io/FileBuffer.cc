// FileBuffer.cc - file loading and zlib wrappers (zlib from Debian's zlib1g-dev).
#include "io/FileBuffer.h"

#include "util/Memory.h"

#include <fluidsurf/Error.h>

#include <tbb/parallel_for.h>
#include <zlib.h>

#include <algorithm>
#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <memory>
#include <sys/stat.h>
#include <unistd.h>

namespace fluidsurf {
namespace io_internal {

namespace {
/// The refusals of a path that is not a regular file we can read: InputError.
void checkRegularFile(const std::string& path, struct stat& st)
{
    if (::stat(path.c_str(), &st) != 0)
        throw InputError(path + ": cannot open: " + std::strerror(errno));
    if (S_ISDIR(st.st_mode)) throw InputError(path + ": is a directory, not a file");
    // A FIFO would block forever and a device (/dev/zero, /dev/urandom) never ends: only
    // regular files are read, and their size is known before the first byte.
    if (!S_ISREG(st.st_mode))
        throw InputError(path + ": not a regular file (a FIFO, device or socket); fluidsurf reads "
                                "regular files only");
}
} // namespace

std::vector<uint8_t> readFile(const std::string& path, const HeadCheck& check)
{
    const OpenFile file(path);
    const size_t size = size_t(file.size()), head = std::min<size_t>(size, 4096);
    std::vector<uint8_t> data(head);
    file.readAt(0, data.data(), head);
    if (check && head > 0) check(data.data(), head, uint64_t(size));
    // the rest on all threads, into pages faulted in on all threads (fread on one thread, after
    // a zero fill, was most of reading a binary PLY: 0.67 s of the 13.1M drop's 157 MB on 16
    // threads, 0.23 s with the parse on all threads)
    util::resizeInParallel(data, size);
    file.readAt(head, data.data() + head, size - head);
    // Anything beyond the stat size (a file still growing) is read on in pieces.
    uint8_t piece[1 << 16];
    for (size_t n; (n = file.readSome(data.size(), piece, sizeof piece)) > 0;)
        data.insert(data.end(), piece, piece + n);
    return data;
}

OpenFile::OpenFile(const std::string& path) : mPath(path)
{
    struct stat st;
    checkRegularFile(path, st);
    mFd = ::open(path.c_str(), O_RDONLY | O_CLOEXEC);
    if (mFd < 0) throw InputError(path + ": cannot open: " + std::strerror(errno));
    mSize = uint64_t(st.st_size);
}

OpenFile::~OpenFile()
{
    if (mFd >= 0) ::close(mFd);
}

void OpenFile::readAt(uint64_t offset, void* dst, size_t n) const
{
    constexpr size_t kChunk = size_t(4) << 20; // 4 MiB: a thread's share, big enough for one call
    const size_t chunks = (n + kChunk - 1) / kChunk;
    std::atomic<int> error{0}; // errno of a failed read; -1: the file ended sooner
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
        uint8_t* to = static_cast<uint8_t*>(dst) + c * kChunk;
        size_t left = std::min(kChunk, n - c * kChunk);
        uint64_t at = offset + c * kChunk;
        while (left > 0 && error.load(std::memory_order_relaxed) == 0) {
            const ssize_t got = ::pread(mFd, to, left, off_t(at));
            if (got < 0 && errno == EINTR) continue;
            if (got <= 0) {
                int expected = 0;
                error.compare_exchange_strong(expected, got < 0 ? errno : -1);
                break;
            }
            to += got, at += uint64_t(got), left -= size_t(got);
        }
    });
    if (error == -1)
        throw InputError(mPath + ": the file ended at fewer than the " +
                         std::to_string(offset + n) +
                         " bytes it had when opened (changed "
                         "while being read?)");
    if (error) throw InputError(mPath + ": read error: " + std::strerror(error));
}

size_t OpenFile::readSome(uint64_t offset, void* dst, size_t n) const
{
    for (;;) {
        const ssize_t got = ::pread(mFd, dst, n, off_t(offset));
        if (got >= 0) return size_t(got);
        if (errno != EINTR) throw InputError(mPath + ": read error: " + std::strerror(errno));
    }
}

bool isGzip(const uint8_t* data, size_t size)
{
    return size >= 2 && data[0] == 0x1f && data[1] == 0x8b;
}

namespace {
/// Inflate until the stream ends or `stop` bytes are out (complete: the stream ended); past
/// maxOutput without ending is an error. With checkTail, the rest of the stream is inflated into
/// a scratch buffer and dropped, so that zlib reaches the CRC (a flipped byte inside the data is
/// an error, not different particles); more than checkTail bytes past stop is an error too.
std::vector<uint8_t> inflateGzip(const uint8_t* data, size_t size, const std::string& source,
                                 size_t maxOutput, size_t stop, bool& complete,
                                 size_t checkTail = 0)
{
    complete = false;
    z_stream zs{};
    if (inflateInit2(&zs, 15 + 16) != Z_OK) throw InputError(source + ": zlib init failed");
    std::vector<uint8_t> out, scratch;
    out.resize(std::min(std::max<size_t>(size * 3, 1 << 16), std::max<size_t>(stop, 1)));
    zs.next_in = const_cast<Bytef*>(data);
    size_t consumed = 0;
    int ret = Z_OK;
    // zlib's avail_in is 32-bit: feed large inputs in slices.
    while (true) {
        if (zs.avail_in == 0 && consumed < size) {
            const size_t slice = std::min<size_t>(size - consumed, 1u << 30);
            zs.next_in = const_cast<Bytef*>(data + consumed);
            zs.avail_in = uInt(slice);
            consumed += slice;
        }
        if (zs.total_out >= stop) { // as much as the caller can use
            if (!checkTail) break;
            if (zs.total_out - stop > checkTail) {
                inflateEnd(&zs);
                throw InputError(source + ": gzip data goes on for more than " +
                                 std::to_string(checkTail) +
                                 " bytes past what the header promises (corrupt or a bomb)");
            }
            scratch.resize(1 << 16);
            zs.next_out = scratch.data();
            zs.avail_out = uInt(scratch.size());
        } else {
            if (zs.total_out == out.size()) {
                if (out.size() >= maxOutput) {
                    inflateEnd(&zs);
                    throw InputError(source + ": gzip data expands beyond " +
                                     std::to_string(maxOutput) + " bytes");
                }
                out.resize(std::min({out.size() * 2, maxOutput, stop}));
            }
            const size_t room = std::min<size_t>(out.size() - zs.total_out, 1u << 30);
            zs.next_out = out.data() + zs.total_out;
            zs.avail_out = uInt(room);
        }
        ret = inflate(&zs, Z_NO_FLUSH);
        if (ret == Z_STREAM_END) {
            complete = true;
            break;
        }
        if (ret != Z_OK && ret != Z_BUF_ERROR) {
            const std::string msg = zs.msg ? zs.msg : "corrupt data";
            const size_t at = zs.total_in;
            inflateEnd(&zs);
            throw InputError(source + ": gzip stream is corrupt: " + msg + " (at compressed byte " +
                             std::to_string(at) + ")");
        }
        if (ret == Z_BUF_ERROR && zs.avail_in == 0 && consumed >= size) {
            inflateEnd(&zs);
            throw InputError(source + ": gzip stream is truncated (ends after " +
                             std::to_string(size) + " compressed bytes)");
        }
    }
    out.resize(std::min<size_t>(zs.total_out, out.size()));
    inflateEnd(&zs);
    return out;
}
} // namespace

std::vector<uint8_t> gunzip(const uint8_t* data, size_t size, const std::string& source,
                            size_t maxOutput)
{
    bool complete = false;
    return inflateGzip(data, size, source, maxOutput, ~size_t(0), complete);
}

std::vector<uint8_t> gunzipPrefix(const uint8_t* data, size_t size, const std::string& source,
                                  size_t want, bool& complete, size_t checkTail)
{
    return inflateGzip(data, size, source, size_t(1) << 36, want, complete, checkTail);
}

void zlibInflate(const uint8_t* src, size_t srcSize, uint8_t* dst, size_t dstSize,
                 const std::string& source)
{
    uLongf outLen = uLongf(dstSize);
    const int ret = uncompress(dst, &outLen, src, uLong(srcSize));
    if (ret != Z_OK || outLen != dstSize)
        throw InputError(source + ": zlib-compressed block is corrupt or truncated (" +
                         std::string(ret == Z_OK ? "size mismatch" : zError(ret)) + ")");
}

} // namespace io_internal
} // namespace fluidsurf
