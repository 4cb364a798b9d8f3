// FileBuffer.h - whole-file loading and zlib/gzip helpers shared by the readers and writers.
#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

struct z_stream_s;

namespace fluidsurf {
namespace io_internal {

/// Read a whole regular file; InputError with a clear reason (missing, directory, not a regular
/// file, unreadable).
std::vector<uint8_t> readFile(const std::string& path);

/// A regular file open for reading at any offset, for a reader that puts the bytes where they
/// belong instead of into a buffer first (readFile's refusals; closed when it goes).
class OpenFile
{
public:
    explicit OpenFile(const std::string& path);
    ~OpenFile();
    OpenFile(const OpenFile&) = delete;
    OpenFile& operator=(const OpenFile&) = delete;

    uint64_t size() const { return mSize; }
    /// n bytes from `offset` into dst, in chunks read by all threads (the kernel's copy and the
    /// page faults of fresh memory are most of a raw format's reading): InputError on an error
    /// or when the file ends sooner (it shrank since it was opened).
    void readAt(uint64_t offset, void* dst, size_t n) const;
    /// The first bytes, up to most (fewer in a shorter file): where a header is looked for.
    std::vector<uint8_t> readHead(size_t most) const;

private:
    std::string mPath;
    int mFd = -1;
    uint64_t mSize = 0;
};

/// count records of recordBytes each, from offset on, read a slice of about 1 MiB by each task
/// and handed over as slice(first record, records in the slice, their bytes): a binary
/// reader's records go where they belong with no buffer of the whole file.
template <typename Slice>
void forRecordSlices(const OpenFile& file, uint64_t offset, size_t count, size_t recordBytes,
                     const Slice& slice)
{
    const size_t perSlice = std::max<size_t>(1, (size_t(1) << 20) / recordBytes);
    tbb::parallel_for(size_t(0), (count + perSlice - 1) / perSlice, [&](size_t s) {
        const size_t first = s * perSlice, n = std::min(perSlice, count - first);
        std::vector<uint8_t> records(n * recordBytes);
        file.readAt(offset + first * recordBytes, records.data(), records.size());
        slice(first, n, records.data());
    });
}

bool isGzip(const uint8_t* data, size_t size);

/// A gzip stream inflated as far as its reader asks (no size is trusted up front): a reader
/// inflates what its header promises, a slice at a time, never a bomb's tail. InputError for a
/// corrupt or truncated stream, naming the compressed byte.
class GzipInflater
{
public:
    GzipInflater(const uint8_t* data, size_t size, const std::string& source);
    ~GzipInflater();
    GzipInflater(const GzipInflater&) = delete;
    GzipInflater& operator=(const GzipInflater&) = delete;

    /// The next n bytes into dst; fewer only where the stream ends.
    size_t read(uint8_t* dst, size_t n);
    /// The rest inflated and dropped up to the CRC, which zlib then checks (a flipped byte
    /// inside the data is an error, not different particles). More than limit bytes past what
    /// the header promises (past of them already read) is an InputError.
    void skipToEnd(uint64_t limit, uint64_t past = 0);
    bool ended() const { return mEnded; }
    uint64_t produced() const { return mProduced; }

private:
    const uint8_t* mData;
    size_t mSize, mConsumed = 0;
    uint64_t mProduced = 0;
    std::string mSource;
    std::unique_ptr<z_stream_s> mStream;
    bool mEnded = false;
};

/// The first `want` bytes of a gzip stream (fewer when it ends sooner; complete says whether the
/// whole stream fitted): a reader inflates only what its header promises, never a bomb's tail.
/// checkTail > 0: the rest is inflated and dropped up to the CRC (complete is then true), and
/// more than checkTail bytes of it is an InputError.
std::vector<uint8_t> gunzipPrefix(const uint8_t* data, size_t size, const std::string& source,
                                  size_t want, bool& complete, size_t checkTail = 0);

/// Inflate one zlib block whose decompressed size is known (VTK XML blocks).
void zlibInflate(const uint8_t* src, size_t srcSize, uint8_t* dst, size_t dstSize,
                 const std::string& source);

} // namespace io_internal
} // namespace fluidsurf
