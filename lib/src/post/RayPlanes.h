// RayPlanes.h - the particle-in-component ray test's arithmetic (post/ParticleVolumes), as plain
// math that the CPU (in lanes of 2 or 4 planes, the same operations in the same order) and the
// GPU (cuda/src/RayCrossings.cu) both compile: a triangle across a column of rays as linear
// functions of the ray's (u, v) from the column's corner, and whether a ray crosses it ahead.
#pragma once

#include "util/HostDevice.h"

namespace fluidsurf {
namespace post {

/// Barycentric s and w and the crossing x of one triangle, as linear functions of the ray's
/// (u, v) taken from the column's corner.
struct RayPlane
{
    double su, sv, s0, wu, wv, w0, xa, xs, xw;
};

/// The plane of triangle (a, b, e) for the column whose corner is (cu0, cv0), rays along axis A
/// with (U, V) across; sign: +1 where the triangle faces along the ray, -1 against. False where
/// the triangle is edge-on to the rays.
FLUIDSURF_HD inline bool rayPlane(const double a[3], const double b[3], const double e[3],
                                  double cu0, double cv0, int A, int U, int V, RayPlane& p,
                                  int& sign)
{
    const double ab[3] = {b[0] - a[0], b[1] - a[1], b[2] - a[2]};
    const double ae[3] = {e[0] - a[0], e[1] - a[1], e[2] - a[2]};
    const double n = ab[U] * ae[V] - ab[V] * ae[U]; // the normal along the ray
    if (n == 0) return false;
    const double au = a[U] - cu0, av = a[V] - cv0;
    p = {ae[V] / n,  -ae[U] / n, (av * ae[U] - au * ae[V]) / n,
         -ab[V] / n, ab[U] / n,  (au * ab[V] - av * ab[U]) / n,
         a[A],       ab[A],      ae[A]};
    sign = n > 0 ? 1 : -1;
    return true;
}

/// Whether the ray from (u, v, x0) crosses plane p ahead (at x > x0), and where.
FLUIDSURF_HD inline bool crossesAhead(const RayPlane& p, double u, double v, double x0, double& x)
{
    const double s = p.su * u + p.sv * v + p.s0, w = p.wu * u + p.wv * v + p.w0;
    if (!(s >= 0 && w >= 0 && s + w <= 1)) return false;
    x = p.xa + s * p.xs + w * p.xw;
    return x > x0;
}

} // namespace post
} // namespace fluidsurf
