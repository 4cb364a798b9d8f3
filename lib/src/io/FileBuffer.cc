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

std::vector<uint8_t> readFile(const std::string& path)
{
    const OpenFile file(path);
    const size_t size = size_t(file.size()), head = std::min<size_t>(size, 4096);
    std::vector<uint8_t> data(head);
    file.readAt(0, data.data(), head);
    // the rest on all threads, into pages faulted in on all threads (fread on one thread, after
    // a zero fill, was most of reading a binary PLY: 0.67 s of the 13.1M drop's 157 MB on 16
    // threads, 0.23 s with the parse on all threads)
    util::resizeInParallel(data, size);
    file.readAt(head, data.data() + head, size - head);
    // A file still growing is read to the size it had when opened: read on to its end, one
    // that a writer keeps growing was read without end (issue 63).
    return data;
}

OpenFile::OpenFile(const std::string& path) : mPath(path)
{
    if (path.find('\0') != std::string::npos) // (open would read the name up to it)
        throw InputError("input path contains a NUL byte");
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

std::vector<uint8_t> OpenFile::readHead(size_t most) const
{
    std::vector<uint8_t> head(size_t(std::min<uint64_t>(mSize, most)));
    readAt(0, head.data(), head.size());
    return head;
}

bool isGzip(const uint8_t* data, size_t size)
{
    return size >= 2 && data[0] == 0x1f && data[1] == 0x8b;
}

GzipInflater::GzipInflater(const uint8_t* data, size_t size, const std::string& source)
    : mData(data), mSize(size), mSource(source), mStream(new z_stream{})
{
    if (inflateInit2(mStream.get(), 15 + 16) != Z_OK)
        throw InputError(source + ": zlib init failed");
}

GzipInflater::~GzipInflater()
{
    inflateEnd(mStream.get());
}

size_t GzipInflater::read(uint8_t* dst, size_t n)
{
    z_stream& zs = *mStream;
    size_t got = 0;
    while (got < n && !mEnded) {
        // zlib's avail_in and avail_out are 32-bit: large inputs and outputs go in slices
        if (zs.avail_in == 0 && mConsumed < mSize) {
            const size_t slice = std::min<size_t>(mSize - mConsumed, 1u << 30);
            zs.next_in = const_cast<Bytef*>(mData + mConsumed);
            zs.avail_in = uInt(slice);
            mConsumed += slice;
        }
        const size_t room = std::min<size_t>(n - got, 1u << 30);
        zs.next_out = dst + got;
        zs.avail_out = uInt(room);
        const int ret = inflate(&zs, Z_NO_FLUSH);
        got += room - zs.avail_out;
        const size_t at = mConsumed - zs.avail_in; // the next compressed byte
        if (ret == Z_STREAM_END) {
            // members one after the other (`cat a.gz b.gz`, Python's gzip in pieces) are one
            // file, as gzip -d reads them; anything else after a member is left alone, as
            // before
            if (mSize - at >= 2 && mData[at] == 0x1f && mData[at + 1] == 0x8b)
                inflateReset(&zs);
            else
                mEnded = true;
        } else if (ret != Z_OK && ret != Z_BUF_ERROR) {
            throw InputError(mSource +
                             ": gzip stream is corrupt: " + (zs.msg ? zs.msg : "corrupt data") +
                             " (at compressed byte " + std::to_string(at) + ")");
        } else if (ret == Z_BUF_ERROR && zs.avail_in == 0 && mConsumed >= mSize) {
            throw InputError(mSource + ": gzip stream is truncated (ends after " +
                             std::to_string(mSize) + " compressed bytes)");
        }
    }
    mProduced += got;
    return got;
}

void GzipInflater::skipToEnd(uint64_t limit, uint64_t past)
{
    // inflated into a scratch buffer and dropped, so that zlib reaches the CRC
    std::vector<uint8_t> scratch(1 << 16);
    while (!mEnded) {
        if (past > limit)
            throw InputError(mSource + ": gzip data goes on for more than " +
                             std::to_string(limit) +
                             " bytes past what the header promises (corrupt or a bomb)");
        past += read(scratch.data(), scratch.size());
    }
}

std::vector<uint8_t> gunzipPrefix(const uint8_t* data, size_t size, const std::string& source,
                                  size_t want, bool& complete, size_t checkTail)
{
    GzipInflater in(data, size, source);
    std::vector<uint8_t> out(
        std::min(std::max<size_t>(size * 3, 1 << 16), std::max<size_t>(want, 1)));
    size_t have = 0;
    while (have < want && !in.ended()) {
        if (have == out.size()) out.resize(std::min(out.size() * 2, want));
        have += in.read(out.data() + have, out.size() - have);
    }
    out.resize(have);
    if (checkTail) in.skipToEnd(checkTail);
    complete = in.ended();
    return out;
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
