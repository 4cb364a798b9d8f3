// Gradient.h - the field gradient at grid points, for vertex normals
// (thesis eq. 4.10-4.12: central differences; one-sided where a neighbour is outside the band).
#pragma once

#include <openvdb/openvdb.h>

namespace fluidsurf {
namespace mesh {

using FloatAccessor = openvdb::tree::ValueAccessor<const openvdb::FloatTree>;

/// Gradient of phi at voxel ijk in index space (per voxel), from active neighbours only.
inline openvdb::Vec3d indexGradient(FloatAccessor& acc, const openvdb::Coord& ijk)
{
    const float center = acc.getValue(ijk);
    openvdb::Vec3d g(0.0);
    for (int a = 0; a < 3; ++a) {
        openvdb::Coord lo = ijk, hi = ijk;
        lo[a] -= 1, hi[a] += 1;
        float vlo = 0, vhi = 0;
        const bool onLo = acc.probeValue(lo, vlo), onHi = acc.probeValue(hi, vhi);
        if (onLo && onHi) g[a] = 0.5 * (double(vhi) - double(vlo));
        else if (onHi) g[a] = double(vhi) - double(center);
        else if (onLo) g[a] = double(center) - double(vlo);
    }
    return g;
}

} // namespace mesh
} // namespace fluidsurf
