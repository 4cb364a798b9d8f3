// TriangleDistance.h - the exact distance from a point to a triangle (or a segment), shared by
// meshDistance and the decimation's guard on how far a collapse moves the surface.
#pragma once

#include "util/Vec3d.h"

#include <algorithm>
#include <cmath>

namespace fluidsurf {

inline double segmentDistance(const Vec3d& p, const Vec3d& a, const Vec3d& b)
{
    const Vec3d ab = b - a;
    const double len2 = ab.lengthSqr();
    const double t = len2 > 0 ? std::clamp((p - a).dot(ab) / len2, 0.0, 1.0) : 0.0;
    return (a + ab * t - p).length();
}

/// To the plane where p projects inside the triangle, else to the nearest side.
inline double triangleDistance(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c)
{
    const Vec3d n = (b - a).cross(c - a);
    const double n2 = n.lengthSqr();
    if (n2 > 0) {
        const double h = (p - a).dot(n) / n2;
        const Vec3d q = p - n * h;
        if ((b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
            (a - c).cross(q - c).dot(n) >= 0)
            return std::abs(h) * std::sqrt(n2);
    }
    return std::min({segmentDistance(p, a, b), segmentDistance(p, b, c), segmentDistance(p, c, a)});
}

/// triangleDistance(p, a, b, c) <= bound, with squares and early outs: far from the plane
/// means far from the triangle, and any near side will do.
inline bool withinDistance(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                           double bound)
{
    const double bound2 = bound * bound;
    const Vec3d n = (b - a).cross(c - a);
    const double n2 = n.lengthSqr();
    if (n2 > 0) {
        const double h = (p - a).dot(n);
        if (h * h > bound2 * n2) return false;
        const Vec3d q = p - n * (h / n2);
        if ((b - a).cross(q - a).dot(n) >= 0 && (c - b).cross(q - b).dot(n) >= 0 &&
            (a - c).cross(q - c).dot(n) >= 0)
            return true;
    }
    auto side2 = [&](const Vec3d& u, const Vec3d& v) {
        const Vec3d uv = v - u;
        const double len2 = uv.lengthSqr();
        const double t = len2 > 0 ? std::clamp((p - u).dot(uv) / len2, 0.0, 1.0) : 0.0;
        return (u + uv * t - p).lengthSqr();
    };
    return side2(a, b) <= bound2 || side2(b, c) <= bound2 || side2(c, a) <= bound2;
}

} // namespace fluidsurf
