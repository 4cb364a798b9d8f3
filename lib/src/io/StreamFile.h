// StreamFile.h - an output file written as its bytes come (no whole-file buffer), atomically:
// into a temporary beside the target, renamed over it by commit() (AtomicFile). Writers that
// produce large outputs (meshes) encode a bounded block at a time and hand it over here.
#pragma once

#include <fluidsurf/io/AtomicFile.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdio>
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

    /// OutputError (naming the target) when the bytes cannot be written.
    void write(const void* data, size_t size);
    void write(const std::string& s) { write(s.data(), s.size()); }
    /// Flush, close and rename over the target; without it the destructor removes the temporary.
    void commit();

private:
    AtomicFile mFile;
    std::FILE* mStream = nullptr;
};

/// Items [0, count) encoded by item(std::string& out, i), in chunks of 8192 items in parallel, 32
/// chunks at a time, written in order: the same bytes for any thread count, and at most one block
/// of text in memory.
template <typename F> void writeItems(StreamFile& out, size_t count, size_t bytesPerItem, F&& item)
{
    constexpr size_t kChunk = 8192, kChunksPerBlock = 32;
    std::vector<std::string> chunks(kChunksPerBlock);
    for (size_t block = 0; block < count; block += kChunk * kChunksPerBlock) {
        const size_t end = std::min(count, block + kChunk * kChunksPerBlock);
        const size_t n = (end - block + kChunk - 1) / kChunk;
        tbb::parallel_for(size_t(0), n, [&](size_t c) {
            std::string& s = chunks[c];
            s.clear();
            s.reserve(kChunk * bytesPerItem);
            for (size_t i = block + c * kChunk, e = std::min(end, i + kChunk); i < e; ++i)
                item(s, i);
        });
        for (size_t c = 0; c < n; ++c)
            out.write(chunks[c]);
    }
}

} // namespace io
} // namespace fluidsurf
