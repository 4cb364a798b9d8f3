// GzipStream.h - a gzip file compressed on all threads as its bytes come (the `.bgeo.gz`
// writer), with no whole-file buffer. zlib on one thread made 2 MB of `.bgeo.gz` a second per
// core: 7.3 s and 640 MB for the 13.1M drop's 210 MB, against 0.4 s and 170 MB for `.bgeo`.
#pragma once

#include <cstddef>
#include <cstdint>
#include <deque>
#include <memory>
#include <string>
#include <vector>

namespace fluidsurf {
namespace io {

class StreamFile;

/// The input is cut into pieces of kPiece bytes, and each piece is deflated by a task of its
/// own as soon as it is full, primed with the 32 KiB before it (deflate's whole window, so a
/// piece finds the matches that one stream would) and ended on a byte boundary by a sync flush.
/// The pieces are written in order as they come back, joined into one deflate stream, and their
/// CRCs into one (crc32_combine). The result is one gzip member, which every gzip reader takes,
/// with the same bytes for any thread count. Memory: at most two pieces a thread in flight, with
/// their output.
class GzipStream
{
public:
    /// The gzip header goes to out at once; level is zlib's (1 fastest .. 9 smallest).
    explicit GzipStream(StreamFile& out, int level = 6);
    /// Waits for the pieces still in flight (after an error, their output is dropped).
    ~GzipStream();
    GzipStream(const GzipStream&) = delete;
    GzipStream& operator=(const GzipStream&) = delete;

    void write(const void* data, size_t size);
    void write(const std::string& s) { write(s.data(), s.size()); }
    /// The last piece, then the trailer (CRC and length). Before out.commit(); nothing may be
    /// written after it.
    void finish();

    static constexpr size_t kPiece = size_t(1) << 20;

private:
    struct Piece;
    /// mFilling to a task; last: the final piece, which ends the stream.
    void submit(bool last);
    /// The oldest piece in flight written (waiting for it first where wait is set); false when
    /// it is not done and wait is not set.
    bool retire(bool wait);

    StreamFile& mOut;
    int mLevel;
    std::string mFilling;                       ///< the piece being filled
    std::string mWindow;                        ///< the 32 KiB before it (its dictionary)
    std::deque<std::unique_ptr<Piece>> mFlight; ///< submitted, in order, not yet written
    size_t mMaxFlight;
    uint32_t mCrc = 0;
    uint64_t mLength = 0; ///< bytes in, for the trailer (mod 2^32 there)
    bool mFinished = false;
};

} // namespace io
} // namespace fluidsurf
