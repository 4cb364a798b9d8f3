// LeafBits.h - a VDB float leaf as bit words and raw values, for marching cubes: active and
// inside (phi < 0) voxels as 8 words of 64 bits (word x, bit y * 8 + z, OpenVDB's leaf order), so
// that edges and cells are tested 64 at a time; and a leaf with its six face neighbours, for
// gradients without OpenVDB's per-value getters (several times slower here).
#pragma once

#include "mesh/Gradient.h"
#include "util/LeafWords.h"

#include <openvdb/openvdb.h>

#include <cstdint>

namespace fluidsurf {
namespace mesh {

using FloatLeaf = openvdb::FloatTree::LeafNodeType;

/// A leaf's active and inside (phi < 0) voxels as bit words (util/LeafWords.h). Cells and edges
/// that stay inside the leaf are found for 64 (y, z) positions at once.
using LeafBits = util::LeafWords;
using util::kY7;
using util::kYBelow7;
using util::kZ0;
using util::kZ7;
using util::kZBelow7;
// Two planes of one x side by side in one word, so squareAll/Any see cells across a leaf face:
// this leaf's row y = 7 as row 0 and the +y neighbour's row 0 as row 1; or column z = 7 as
// column 0 and the +z neighbour's column 0 as column 1.
inline uint64_t acrossY(uint64_t w, uint64_t plusY)
{
    return w >> 56 | plusY << 8;
}
inline uint64_t acrossZ(uint64_t w, uint64_t plusZ)
{
    return (w >> 7 & kZ0) | (plusZ & kZ0) << 1;
}
/// Bit (y, z) set when bits (y, z), (y, z+1), (y+1, z), (y+1, z+1) all are / any is.
inline uint64_t squareAll(uint64_t w)
{
    return w & w >> 1 & w >> 8 & w >> 9;
}
inline uint64_t squareAny(uint64_t w)
{
    return w | w >> 1 | w >> 8 | w >> 9;
}

/// A linear transform as a matrix: index -> world, and its inverse Jacobian for gradients.
/// A leaf and its six face neighbours as raw values and active bits (OpenVDB's per-value getters
/// cost several times more here), for gradients at the leaf's voxels.
struct LeafStar
{
    const float* values[7] = {}; // 0: the leaf; 1 + 2 * axis + (0: -axis, 1: +axis); null: none
    const LeafBits* bits[7] = {};

    /// Value and active state at local l, whose coordinate along axis may be -1 or 8.
    bool read(openvdb::Coord l, int axis, float& v) const
    {
        int k = 0;
        if (l[axis] < 0)
            k = 1 + 2 * axis, l[axis] += FloatLeaf::DIM;
        else if (l[axis] >= int(FloatLeaf::DIM))
            k = 2 + 2 * axis, l[axis] -= FloatLeaf::DIM;
        if (!values[k]) return false;
        const int i = l.x() << 6 | l.y() << 3 | l.z();
        v = values[k][i];
        return bits[k]->active[i >> 6] >> (i & 63) & 1;
    }
    /// Gradient of phi (index space) at local l in [0, 7]^3: central differences between active
    /// neighbours, one-sided where one is missing.
    openvdb::Vec3d gradient(const openvdb::Coord& l) const
    {
        return activeGradient(
            l, values[0][l.x() << 6 | l.y() << 3 | l.z()],
            [this](const openvdb::Coord& c, int axis, float& v) { return read(c, axis, v); });
    }
};

} // namespace mesh
} // namespace fluidsurf
