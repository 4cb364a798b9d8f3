// Vec3d.h - the double-precision vector that mesh computations run in (OpenVDB's), and the
// conversions from and to the mesh's float points.
#pragma once

#include <fluidsurf/Vec3.h>

#include <openvdb/Types.h>

namespace fluidsurf {

using Vec3d = openvdb::Vec3d;

inline Vec3d toVec3d(const Vec3f& p)
{
    return {p.x, p.y, p.z};
}

/// For code over either kind of point.
inline Vec3d toVec3dAny(const Vec3f& p)
{
    return toVec3d(p);
}
inline const Vec3d& toVec3dAny(const Vec3d& p)
{
    return p;
}

inline Vec3f toVec3f(const Vec3d& p)
{
    return {float(p[0]), float(p[1]), float(p[2])};
}

} // namespace fluidsurf
