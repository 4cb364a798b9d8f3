// Gradient.h - the field gradient at grid points, for vertex normals
// (thesis eq. 4.10-4.12: central differences; one-sided where a neighbour is outside the band).
#pragma once

#include "mesh/GradientMath.h"

#include <openvdb/openvdb.h>

namespace fluidsurf {
namespace mesh {

using FloatAccessor = openvdb::tree::ValueAccessor<const openvdb::FloatTree>;

/// Gradient of phi (index space) at a voxel with value center: read(neighbour, axis, value)
/// gives a neighbour's value and whether it is active. Central differences between active
/// neighbours, one-sided where one of them is missing (thesis eq. 4.10-4.12).
template <typename Read>
inline openvdb::Vec3d activeGradient(const openvdb::Coord& ijk, float center, Read&& read)
{
    openvdb::Vec3d g(0.0);
    for (int a = 0; a < 3; ++a) {
        openvdb::Coord lo = ijk, hi = ijk;
        lo[a] -= 1, hi[a] += 1;
        float vlo = 0, vhi = 0;
        const bool onLo = read(lo, a, vlo), onHi = read(hi, a, vhi);
        g[a] = centralDifference(onLo, vlo, onHi, vhi, center);
    }
    return g;
}

/// The same through an accessor, at any voxel.
inline openvdb::Vec3d indexGradient(FloatAccessor& acc, const openvdb::Coord& ijk)
{
    return activeGradient(ijk, acc.getValue(ijk), [&](const openvdb::Coord& c, int, float& v) {
        return acc.probeValue(c, v);
    });
}

} // namespace mesh
} // namespace fluidsurf
