// ObjInParallel.cc - OBJ meshes read on all threads (see ObjInParallel.h).
//
// The file is cut into pieces at line ends. Each piece counts its vertices, normals and
// triangles first: that places its output in the mesh's arrays, and a negative index counts
// back from the vertices before it. Then each piece is read into its place. (Line by line on
// one thread, each word a string, the 1.7M-particle frame's 158 MB raw mesh took 1.0-1.3 s of
// `post`'s 2.3-2.7 s on 2 cores.)
#include "io/ObjInParallel.h"

#include "io/Formats.h"
#include "io/Polygon.h"
#include "io/TextParse.h"

#include "util/Memory.h"

#include <tbb/parallel_for.h>

#include <atomic>
#include <cstring>
#include <utility>
#include <vector>

namespace fluidsurf {
namespace io_internal {

namespace {

/// The whitespace-delimited words of one line [p, end), as readObj splits it.
class Words
{
public:
    Words(const char* p, const char* end) : mP(p), mEnd(end) {}
    /// The next word into [b, e); false at the line's end.
    bool next(const char*& b, const char*& e)
    {
        while (mP < mEnd && isSpace(uint8_t(*mP)))
            ++mP;
        if (mP == mEnd) return false;
        b = mP;
        while (mP < mEnd && !isSpace(uint8_t(*mP)))
            ++mP;
        e = mP;
        return true;
    }

private:
    const char *mP, *mEnd;
};

bool isWord(const char* b, const char* e, const char* word)
{
    const size_t n = std::strlen(word);
    return size_t(e - b) == n && std::memcmp(b, word, n) == 0;
}

/// One piece of an OBJ file: its bytes (from a line's start to after a line end) and where its
/// vertices, normals and triangles go (the counts of the pieces before it).
struct ObjPiece
{
    size_t begin = 0, end = 0;
    size_t points = 0, normals = 0, triangles = 0;
};

} // namespace

bool readObjInParallel(const uint8_t* data, size_t size, TriangleMesh& out)
{
    constexpr size_t kPiece = size_t(1) << 20;
    const char* text = reinterpret_cast<const char*>(data);
    std::vector<ObjPiece> pieces;
    for (size_t at = 0; at < size;) {
        const void* nl = at + kPiece < size
                             ? std::memchr(text + at + kPiece, '\n', size - at - kPiece)
                             : nullptr;
        const size_t end = nl ? size_t(static_cast<const char*>(nl) - text) + 1 : size;
        pieces.push_back({at, end});
        at = end;
    }
    // each line of a piece as readObj takes it; false stops (and a line too long to be sure of)
    auto forEachLine = [&](const ObjPiece& piece, auto&& line) {
        for (size_t at = piece.begin; at < piece.end;) {
            const void* nl = std::memchr(text + at, '\n', piece.end - at);
            const size_t end = nl ? size_t(static_cast<const char*>(nl) - text) : piece.end;
            if (end - at >= kObjLineLimit || !line(Words(text + at, text + end))) return false;
            at = end + 1;
        }
        return true;
    };
    std::atomic<bool> refused{false};
    tbb::parallel_for(size_t(0), pieces.size(), [&](size_t k) {
        ObjPiece& piece = pieces[k];
        const bool counted = forEachLine(piece, [&](Words w) {
            const char *b, *e;
            if (!w.next(b, e)) return true;
            piece.points += isWord(b, e, "v");
            piece.normals += isWord(b, e, "vn");
            if (isWord(b, e, "f")) {
                size_t corners = 0;
                while (w.next(b, e))
                    ++corners;
                if (corners < 3) return false;
                piece.triangles += corners - 2;
            }
            return true;
        });
        if (!counted) refused = true;
    });
    if (refused) return false;
    ObjPiece total;
    for (ObjPiece& piece : pieces) {
        total.points += std::exchange(piece.points, total.points);
        total.normals += std::exchange(piece.normals, total.normals);
        total.triangles += std::exchange(piece.triangles, total.triangles);
    }
    // normals are kept when there is one per vertex (as fluidsurf writes them: f v//v)
    const bool withNormals = total.normals == total.points;
    util::resizeInParallel(out.points, total.points);
    if (withNormals) util::resizeInParallel(out.normals, total.normals);
    util::resizeInParallel(out.triangles, total.triangles);
    tbb::parallel_for(size_t(0), pieces.size(), [&](size_t k) {
        ObjPiece at = pieces[k]; // where the next of each goes
        std::vector<uint32_t> face;
        const bool read = forEachLine(pieces[k], [&](Words w) {
            if (refused.load(std::memory_order_relaxed)) return false;
            const char *b, *e;
            if (!w.next(b, e) || *b == '#') return true;
            const bool v = isWord(b, e, "v");
            if (v || isWord(b, e, "vn")) {
                Vec3f p;
                for (int a = 0; a < 3; ++a) {
                    double d;
                    if (!w.next(b, e) || !parseFloat(b, e, d)) return false;
                    p[a] = float(d);
                }
                if (v)
                    out.points[at.points++] = p;
                else if (withNormals)
                    out.normals[at.normals++] = p;
            } else if (isWord(b, e, "f")) {
                const int64_t n = int64_t(at.points); // the vertices read so far
                face.clear();
                while (w.next(b, e)) {
                    const void* slash = std::memchr(b, '/', size_t(e - b));
                    int64_t i;
                    if (!parseInt(b, slash ? static_cast<const char*>(slash) : e, i) || i == 0)
                        return false;
                    if (i < 0) i += n + 1;
                    if (i < 1 || i > n) return false;
                    face.push_back(uint32_t(i - 1));
                }
                triangulatePolygon(face.data(), face.size(),
                                   [&](uint32_t a, uint32_t b, uint32_t c) {
                                       out.triangles[at.triangles++] = {a, b, c};
                                   });
            }
            return true;
        });
        if (!read) refused = true;
    });
    return !refused;
}

} // namespace io_internal
} // namespace fluidsurf
