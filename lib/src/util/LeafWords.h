// LeafWords.h - a VDB float leaf's voxels as 8 words of 64 bits: word x, bit y * 8 + z (OpenVDB's
// leaf order). Neighbours along z are adjacent bits, along y 8 bits apart, along x the next
// word, so that edges and cells are tested 64 at a time: marching cubes (mesh/LeafBits.h) and
// band completion's frontier scan (field/LeafBits.h).
#pragma once

#include <openvdb/openvdb.h>

#include <cstdint>

#include <emmintrin.h>

namespace fluidsurf {
namespace util {

/// A leaf's active and inside (phi < 0) voxels.
struct LeafWords
{
    uint64_t active[8] = {}, in[8] = {};
    LeafWords() = default; // no leaf: nothing active
    explicit LeafWords(const openvdb::FloatTree::LeafNodeType& leaf)
    {
        const auto& mask = leaf.getValueMask();
        for (int x = 0; x < 8; ++x)
            active[x] = mask.template getWord<uint64_t>(x), in[x] = 0;
        const float* v = leaf.buffer().data();
        for (int x = 0; x < 8; ++x)
            in[x] = inWord(v + 64 * x);
    }

    /// The bits of 64 values v[i] < 0 (inside), bit i for v[i].
    static uint64_t inWord(const float* v)
    {
        return wordWhere(v, [](__m128 f) { return _mm_cmplt_ps(f, _mm_setzero_ps()); });
    }

    /// The bits of 64 values v[i] where test (4 at a time: an SSE2 compare) holds, bit i for
    /// v[i]. A compare and a mask move for 4 values, where a value at a time took 4 operations
    /// each (SSE2 is in every x86-64; the compare is IEEE's, NaN false, as the scalar one).
    template <typename Test> static uint64_t wordWhere(const float* v, Test test)
    {
        uint64_t w = 0;
        for (int i = 0; i < 64; i += 4)
            w |= uint64_t(_mm_movemask_ps(test(_mm_loadu_ps(v + i)))) << i;
        return w;
    }
};
constexpr uint64_t kZBelow7 = 0x7F7F7F7F7F7F7F7FULL; // bits with z < 7
constexpr uint64_t kYBelow7 = 0x00FFFFFFFFFFFFFFULL; // bits with y < 7
constexpr uint64_t kZ0 = 0x0101010101010101ULL;      // bits with z = 0
constexpr uint64_t kZ7 = kZ0 << 7, kY7 = 0xFFULL << 56;

/// The bits of one word (a leaf's x) with y in [y0, y1] and z in [z0, z1], leaf-local (0 to 7,
/// y0 <= y1, z0 <= z1): a box of voxels is set a word an x instead of a voxel at a time.
inline uint64_t boxWord(int y0, int y1, int z0, int z1)
{
    const uint64_t zRun = ((uint64_t(2) << (z1 - z0)) - 1) << z0; // < 256: no carries below
    const uint64_t rows = kZ0 >> (8 * (7 - (y1 - y0)));           // one bit a row
    return zRun * (rows << (8 * y0));
}

} // namespace util
} // namespace fluidsurf
