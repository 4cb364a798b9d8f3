// LeafBits.cc - see LeafBits.h.
#include "field/LeafBits.h"

#include "util/LeafWords.h"

#include <cmath>

namespace fluidsurf {
namespace field {

namespace {
using LeafT = FloatLeaf;
using util::kZ0;
using util::kZ7;

/// Bits of one leaf: its active voxels, the negative ones and those with |phi| < threshold.
struct LeafBits
{
    Words active{}, negative{}, near{};
};

LeafBits leafBits(const LeafT& leaf, float threshold)
{
    const util::LeafWords words(leaf);
    LeafBits b;
    const float* v = leaf.buffer().data();
    const __m128 limit = _mm_set1_ps(threshold);
    const __m128 magnitude = _mm_castsi128_ps(_mm_set1_epi32(0x7fffffff)); // |v|: sign bit off
    for (int x = 0; x < 8; ++x) {
        b.active[x] = words.active[x], b.negative[x] = words.in[x];
        b.near[x] = util::LeafWords::wordWhere(
            v + 64 * x, [&](__m128 f) { return _mm_cmplt_ps(_mm_and_ps(f, magnitude), limit); });
    }
    return b;
}

} // namespace

ActiveShell activeShell(const FloatLeaf& home,
                        openvdb::tree::ValueAccessor<const openvdb::FloatTree>& acc)
{
    ActiveShell s; // (each neighbour ORs its bits in: an edge's row is also a face's)
    auto word = [](const LeafT& leaf, int x) {
        return leaf.getValueMask().template getWord<uint64_t>(x);
    };
    for (int x = 0; x < 8; ++x)
        for (int y = 0; y < 8; ++y)
            s.rows[x + 1][y + 1] = uint16_t((word(home, x) >> 8 * y & 0xff) << 1);
    const uint64_t all = ~uint64_t(0);
    for (int dx = -1; dx <= 1; ++dx)
        for (int dy = -1; dy <= 1; ++dy)
            for (int dz = -1; dz <= 1; ++dz) {
                if (!dx && !dy && !dz) continue;
                const openvdb::Coord o = home.origin() + openvdb::Coord(8 * dx, 8 * dy, 8 * dz);
                const LeafT* n = acc.probeConstLeaf(o);
                if (!n && !acc.isValueOn(o)) continue; // nothing active there
                // the neighbour's voxels next to home: x = 7 of the one at dx = -1, and so on
                const int lx = dx < 0 ? 7 : 0, ly = dy < 0 ? 7 : 0, lz = dz < 0 ? 7 : 0;
                const int sx = dx < 0 ? 0 : 9, sy = dy < 0 ? 0 : 9, sz = dz < 0 ? 0 : 9;
                const int faces = !dx + !dy + !dz; // 2: a face, 1: an edge, 0: a corner
                if (faces == 2 && dx) {            // an x face: one word
                    const uint64_t w = n ? word(*n, lx) : all;
                    for (int y = 0; y < 8; ++y)
                        s.rows[sx][y + 1] |= uint16_t((w >> 8 * y & 0xff) << 1);
                } else if (faces == 2 && dy) { // a y face: one byte of each word
                    for (int x = 0; x < 8; ++x)
                        s.rows[x + 1][sy] |=
                            uint16_t(((n ? word(*n, x) : all) >> 8 * ly & 0xff) << 1);
                } else if (faces == 2) { // a z face: one bit of each byte
                    for (int x = 0; x < 8; ++x) {
                        const uint64_t w = n ? word(*n, x) : all;
                        for (int y = 0; y < 8; ++y)
                            s.rows[x + 1][y + 1] |= uint16_t((w >> (8 * y + lz) & 1) << sz);
                    }
                } else { // an edge (8 voxels) or a corner (1)
                    for (int i = 0; i < (faces ? 8 : 1); ++i) {
                        const int x = dx ? lx : i, y = dy ? ly : i, z = dz ? lz : i;
                        if (n && !n->isValueOn(openvdb::Coord(x, y, z))) continue;
                        s.rows[dx ? sx : x + 1][dy ? sy : y + 1] |=
                            uint16_t(1 << (dz ? sz : z + 1));
                    }
                }
            }
    return s;
}

EdgeStencils edgeStencils(const ActiveShell& shell)
{
    // Per row (x, y in [-1, 8]) of z bits (bit z + 1): three in a row along z (z - 1, z, z + 1)
    // and two (z, z + 1); then the 18-corner blocks as ANDs of three rows across x or y.
    uint32_t three[10][10], two[10][10];
    for (int i = 0; i < 10; ++i)
        for (int j = 0; j < 10; ++j) {
            const uint32_t r = shell.rows[i][j];
            three[i][j] = r & r >> 1 & r << 1, two[i][j] = r & r >> 1;
        }
    // acrossX[i][j]: three in a row along z at x - 1, x, x + 1 (i = x + 1, x in [0, 7]); acrossY
    // likewise along y; twoSquare: two along z over the 3x3 rows around (x, y)
    uint32_t acrossX[10][10] = {}, acrossY[10][10] = {}, twoSquare[10][10] = {};
    for (int i = 1; i < 9; ++i)
        for (int j = 0; j < 10; ++j)
            acrossX[i][j] = three[i - 1][j] & three[i][j] & three[i + 1][j];
    for (int i = 0; i < 10; ++i)
        for (int j = 1; j < 9; ++j)
            acrossY[i][j] = three[i][j - 1] & three[i][j] & three[i][j + 1];
    for (int i = 1; i < 9; ++i)
        for (int j = 1; j < 9; ++j)
            twoSquare[i][j] = (two[i - 1][j - 1] & two[i - 1][j] & two[i - 1][j + 1]) &
                              (two[i][j - 1] & two[i][j] & two[i][j + 1]) &
                              (two[i + 1][j - 1] & two[i + 1][j] & two[i + 1][j + 1]);
    auto byte = [](uint32_t r) { return uint64_t(r >> 1 & 0xff); }; // z = 0..7 as bits 0..7
    EdgeStencils e{};
    for (int x = 0; x < 8; ++x)
        for (int y = 0; y < 8; ++y) {
            const int i = x + 1, j = y + 1, at = 8 * y;
            // the edge along x from (x, y): rows x and x + 1, each y - 1..y + 1
            const uint32_t fullX = acrossY[i][j] & acrossY[i + 1][j],
                           belowX = acrossY[i - 1][j] & acrossY[i][j];
            const uint32_t fullY = acrossX[i][j] & acrossX[i][j + 1],
                           belowY = acrossX[i][j - 1] & acrossX[i][j];
            e.full[0][x] |= byte(fullX) << at;
            e.full[1][x] |= byte(fullY) << at;
            e.full[2][x] |= byte(twoSquare[i][j]) << at;
            e.fullBelow[0][x] |= byte(belowX) << at;
            e.fullBelow[1][x] |= byte(belowY) << at;
            e.fullBelow[2][x] |= uint64_t(twoSquare[i][j] & 0xff) << at; // bit z: from z - 1
            e.activeBelow[0][x] |= byte(shell.rows[i - 1][j]) << at;
            e.activeBelow[1][x] |= byte(shell.rows[i][j - 1]) << at;
            e.activeBelow[2][x] |= uint64_t(shell.rows[i][j] & 0xff) << at;
        }
    return e;
}

namespace {

/// The active and negative bits of one face of a leaf (axis, the low face for step > 0, else the
/// high one), in their places; the other bits 0: what a neighbour needs of it.
LeafBits faceBits(const LeafT& leaf, int axis, int step)
{
    LeafBits b;
    const float* v = leaf.buffer().data();
    const int at = step > 0 ? 0 : 7; // the face's x, y or z
    for (int x = 0; x < 8; ++x) {
        if (axis == 0 && x != at) continue;
        uint64_t face = ~uint64_t(0);
        if (axis == 1) face = uint64_t(0xff) << (8 * at);
        if (axis == 2) face = uint64_t(0x0101010101010101ull) << at;
        b.active[x] = leaf.getValueMask().template getWord<uint64_t>(x) & face;
        // The face's signs (the same v < 0 as a voxel at a time, where a chain of bit scans
        // and shifts through the face's 64 voxels was more than half of the frontier
        // candidates' time): an x face is a whole word, 4 at a time; a y face is 8 values in a
        // row of each word, 4 at a time; a z face is one value in 8 of each word, each on its
        // own, no chain.
        const float* w = v + 64 * x;
        if (axis == 0) {
            b.negative[x] = util::LeafWords::inWord(w);
        } else if (axis == 1) {
            const __m128 zero = _mm_setzero_ps();
            const unsigned row =
                unsigned(_mm_movemask_ps(_mm_cmplt_ps(_mm_loadu_ps(w + 8 * at), zero))) |
                unsigned(_mm_movemask_ps(_mm_cmplt_ps(_mm_loadu_ps(w + 8 * at + 4), zero))) << 4;
            b.negative[x] = uint64_t(row) << (8 * at);
        } else {
            uint64_t neg = 0;
            for (int y = 0; y < 8; ++y)
                neg |= uint64_t(w[8 * y + at] < 0) << (8 * y + at);
            b.negative[x] = neg;
        }
    }
    return b;
}

} // namespace

Directions frontierCandidates(const FloatLeaf& home, float threshold,
                              openvdb::tree::ValueAccessor<const openvdb::FloatTree>& acc)
{
    const LeafBits own = leafBits(home, threshold);
    Directions out{};
    // The neighbour in direction (axis, step) of every voxel, as bits at the voxel's place.
    auto visit = [&](int dir, const Words& active, const Words& negative) {
        for (int x = 0; x < 8; ++x)
            out[dir][x] = own.active[x] & ((own.near[x] & ~active[x]) |
                                           (active[x] & (own.negative[x] ^ negative[x])));
    };
    for (int axis = 0; axis < 3; ++axis)
        for (int step : {-1, 1}) {
            openvdb::Coord o = home.origin();
            o[axis] += 8 * step;
            const LeafT* other = acc.probeConstLeaf(o);
            if (!other && acc.isValueOn(o)) { // a tile: scan every voxel
                out.fill(own.active);
                return out;
            }
            const LeafBits nb = other ? faceBits(*other, axis, step) : LeafBits{};
            Words a{}, n{};
            for (int x = 0; x < 8; ++x) {
                if (axis == 0) { // whole words: the next or previous x, or the other leaf's
                    const int from = x + step;
                    const bool inside = from >= 0 && from < 8;
                    a[x] = inside ? own.active[from] : nb.active[from & 7];
                    n[x] = inside ? own.negative[from] : nb.negative[from & 7];
                } else if (axis == 1) { // y is bits 8 apart: shift, and the face row
                    a[x] = step > 0 ? own.active[x] >> 8 | nb.active[x] << 56
                                    : own.active[x] << 8 | nb.active[x] >> 56;
                    n[x] = step > 0 ? own.negative[x] >> 8 | nb.negative[x] << 56
                                    : own.negative[x] << 8 | nb.negative[x] >> 56;
                } else { // z is adjacent bits within each row of 8
                    a[x] = step > 0 ? (own.active[x] >> 1 & ~kZ7) | (nb.active[x] & kZ0) << 7
                                    : (own.active[x] << 1 & ~kZ0) | (nb.active[x] & kZ7) >> 7;
                    n[x] = step > 0 ? (own.negative[x] >> 1 & ~kZ7) | (nb.negative[x] & kZ0) << 7
                                    : (own.negative[x] << 1 & ~kZ0) | (nb.negative[x] & kZ7) >> 7;
                }
            }
            visit(2 * axis + (step > 0), a, n);
        }
    return out;
}

} // namespace field
} // namespace fluidsurf
