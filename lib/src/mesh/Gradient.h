// Gradient.h - the field gradient at grid points and along cell edges, for vertex normals
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

/// Unit outward normal in world space at the point t of the way from voxel a to its neighbour b
/// (index-space gradient interpolated, then mapped by the transform's inverse Jacobian
/// transpose). Falls back to the edge direction, from inside to outside, where the gradient
/// vanishes.
inline openvdb::Vec3f edgeNormal(FloatAccessor& acc, const openvdb::math::Transform& xform, const openvdb::Coord& a,
                                 const openvdb::Coord& b, double t, float valueA)
{
    openvdb::Vec3d g = indexGradient(acc, a) * (1 - t) + indexGradient(acc, b) * t;
    const openvdb::Vec3d p = a.asVec3d() * (1 - t) + b.asVec3d() * t;
    g = xform.baseMap()->applyIJT(g, p);  // p: index space, the map's domain
    if (!(g.lengthSqr() > 0)) g = (b.asVec3d() - a.asVec3d()) * (valueA < 0 ? 1.0 : -1.0);
    g.normalize();
    return openvdb::Vec3f(g);
}

} // namespace mesh
} // namespace fluidsurf
