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

Words activeOf(const LeafT& leaf)
{
    Words w;
    for (int x = 0; x < 8; ++x)
        w[x] = leaf.getValueMask().template getWord<uint64_t>(x);
    return w;
}

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

Words shiftedWords(const Words& w, int dx, int dy, int dz)
{
    Words out{};
    for (int x = 0; x < 8; ++x) {
        if (x + dx < 0 || x + dx > 7) continue;
        uint64_t v = w[x + dx];
        v = dy > 0 ? v >> 8 : dy < 0 ? v << 8 : v;
        v = dz > 0 ? (v >> 1) & ~kZ7 : dz < 0 ? (v << 1) & ~kZ0 : v;
        out[x] = v;
    }
    return out;
}

std::array<Words, 3> fullStencils(const Words& active)
{
    // The 2x3x3 block of an edge along `axis` is separable: erode along each of the other two
    // axes in turn (a voxel stays where both its neighbours along that axis are active), then
    // along `axis` keep the voxels whose next one stayed too. 15 shifts of the words instead of
    // 54 (the 18 corners per axis shifted one by one were a twelfth of the frontier scan).
    auto erode = [](const Words& w, int axis) {
        int o[3] = {0, 0, 0};
        o[axis] = 1;
        const Words up = shiftedWords(w, o[0], o[1], o[2]);
        const Words down = shiftedWords(w, -o[0], -o[1], -o[2]);
        Words out;
        for (int x = 0; x < 8; ++x)
            out[x] = w[x] & up[x] & down[x];
        return out;
    };
    const Words line[3] = {erode(active, 0), erode(active, 1), erode(active, 2)};
    std::array<Words, 3> full;
    for (int axis = 0; axis < 3; ++axis) {
        const int b = (axis + 1) % 3, d = (axis + 2) % 3;
        const Words square = erode(line[b], d); // the 3x3 block across the axis
        int o[3] = {0, 0, 0};
        o[axis] = 1;
        const Words next = shiftedWords(square, o[0], o[1], o[2]);
        for (int x = 0; x < 8; ++x)
            full[axis][x] = square[x] & next[x];
    }
    return full;
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
        uint64_t neg = 0;
        for (uint64_t bits = face; bits; bits &= bits - 1) {
            const int i = __builtin_ctzll(bits);
            neg |= uint64_t(v[64 * x + i] < 0) << i;
        }
        b.negative[x] = neg;
    }
    return b;
}

} // namespace

Words activeWords(const FloatLeaf& leaf)
{
    return activeOf(leaf);
}

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
