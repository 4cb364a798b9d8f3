// StreamFile.h - an output file written as its bytes come (no whole-file buffer), atomically:
// into a temporary beside the target, renamed over it by commit() (AtomicFile). Writers that
// produce large outputs (meshes) encode a bounded block at a time and hand it over here.
#pragma once

#include <fluidsurf/io/AtomicFile.h>

#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <algorithm>
#include <cstdint>
#include <string>
#include <vector>

namespace fluidsurf {
namespace io {

class StreamFile
{
public:
    /// Opens the temporary for path; OutputError when it cannot be created.
    explicit StreamFile(const std::string& path);
    ~StreamFile();
    StreamFile(const StreamFile&) = delete;
    StreamFile& operator=(const StreamFile&) = delete;

    /// OutputError (naming the target) when the bytes cannot be written. Straight to the file
    /// (no buffer of our own: writers hand over blocks of hundreds of KB). Every kWriteBack
    /// bytes, the disk is asked to start writing what came so far, so that commit's fsync
    /// waits for the last part only: on the GPU machine the 13.1M drop's 78 MB PLY spent
    /// 0.039 s of the writer's 0.095 s in fsync after the last byte.
    void write(const void* data, size_t size);
    void write(const std::string& s) { write(s.data(), s.size()); }
    /// fsync, rename over the target, then close (the lock on the temporary goes last);
    /// without it the destructor removes the temporary.
    void commit();

    static constexpr uint64_t kWriteBack = uint64_t(8) << 20;

private:
    AtomicFile mFile;
    int mFd;                                 ///< mFile's temporary
    uint64_t mWritten = 0, mWrittenBack = 0; ///< bytes written, and handed to the disk
};

/// Items [0, count) encoded by item(std::string& out, i), in chunks of 8192 items in parallel, 32
/// chunks a block, written in order to out (a StreamFile, or anything with write(std::string)):
/// the same bytes for any thread count, and at most two blocks of text in memory. The next block is
/// encoded on the other threads while this one writes the last (one after the other, encoding was a
/// fifth of a 16-thread write of the 13.1M drop's PLY).
template <typename Out, typename F>
void writeItems(Out& out, size_t count, size_t bytesPerItem, F&& item)
{
    constexpr size_t kChunk = 8192, kChunksPerBlock = 32, kBlock = kChunk * kChunksPerBlock;
    std::vector<std::string> chunks[2] = {std::vector<std::string>(kChunksPerBlock),
                                          std::vector<std::string>(kChunksPerBlock)};
    size_t used[2] = {0, 0}; // each block's chunks
    auto encode = [&](size_t block, int to) {
        const size_t end = std::min(count, block + kBlock);
        used[to] = (end - block + kChunk - 1) / kChunk;
        tbb::parallel_for(size_t(0), used[to], [&](size_t c) {
            std::string& s = chunks[to][c];
            s.clear();
            s.reserve(kChunk * bytesPerItem);
            for (size_t i = block + c * kChunk, e = std::min(end, i + kChunk); i < e; ++i)
                item(s, i);
        });
    };
    if (count > 0) encode(0, 0);
    tbb::task_group next;
    int at = 0;
    for (size_t block = 0; block < count; block += kBlock, at ^= 1) {
        if (block + kBlock < count)
            next.run([&encode, block, at] { encode(block + kBlock, at ^ 1); });
        try {
            for (size_t c = 0; c < used[at]; ++c)
                out.write(chunks[at][c]);
        } catch (...) {
            next.wait(); // (it reads the caller's data)
            throw;
        }
        next.wait();
    }
}

} // namespace io
} // namespace fluidsurf
