// GzipStream.h - a gzip file compressed on all threads as its bytes come (the `.bgeo.gz`
// writer), with no whole-file buffer. zlib takes in about 30 MB a second on one thread: the
// whole file on one thread was 7.3-8.6 s and 640 MB for the 13.1M drop's 210 MB on 2 cores,
// against 0.4 s and 170 MB for `.bgeo`.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace fluidsurf {
namespace io {

class StreamFile;

/// The input is cut into pieces of kPiece bytes, and each piece is deflated on a thread of its
/// own, primed with the 32 KiB before it (deflate's whole window, so a piece finds the matches
/// that one stream would) and ended on a byte boundary by a sync flush. The pieces then join
/// into one deflate stream, and their CRCs into one (crc32_combine). The result is one gzip
/// member, which every gzip reader takes, with the same bytes for any thread count. Memory: a
/// batch of pieces and their output, a few MB a thread.
class GzipStream
{
public:
    /// The gzip header goes to out at once; level is zlib's (1 fastest .. 9 smallest).
    explicit GzipStream(StreamFile& out, int level = 6);

    void write(const void* data, size_t size);
    void write(const std::string& s) { write(s.data(), s.size()); }
    /// The last piece, then the trailer (CRC and length). Before out.commit(); nothing may be
    /// written after it.
    void finish();

    static constexpr size_t kPiece = size_t(1) << 20;

private:
    /// Deflates the waiting pieces on all threads and writes them in order; last: the final
    /// piece, which ends the stream.
    void compressBatch(bool last);

    StreamFile& mOut;
    int mLevel;
    std::vector<std::string> mBatch; ///< full pieces waiting, and the one being filled last
    std::string mWindow;             ///< the 32 KiB before mBatch's first piece (its dictionary)
    uint32_t mCrc = 0;
    uint64_t mLength = 0; ///< bytes in, for the trailer (mod 2^32 there)
    size_t mBatchPieces;
    bool mFinished = false;
};

} // namespace io
} // namespace fluidsurf
