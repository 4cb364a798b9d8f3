// Quadric.h - Garland and Heckbert's quadric error: the weighted sum of squared distances from a
// point to a set of planes, kept as a symmetric 3x3 matrix, a vector and a constant so that sets
// merge by addition (the error of a collapsed vertex is the error to all planes it replaced).
#pragma once

#include "util/Vec3d.h"

namespace fluidsurf {
namespace post {

/// Always inlined: a batch of edges (post/CollapseBatch) runs these on vectors in code compiled
/// for AVX2, which only an inlined body takes on.
#define FLUIDSURF_QUADRIC_INLINE __attribute__((always_inline)) inline

/// T: double, or a vector of doubles (util::Doubles, util::WideDoubles) for several quadrics at
/// once, lane by lane. Each lane then goes through the same operations in the same order as a
/// double alone, and there is no FMA in either (the build targets no CPU that has it), so a
/// lane's bits are the double's. Branches are selects for the same reason: `c ? x : y` takes a
/// vector of lane masks as well as a bool.
template <typename T> struct BasicQuadric
{
    // No initialisers: an array of a million is filled in parallel without being zeroed first
    // (Quadric{} is the empty set of planes).
    T a00, a01, a02, a11, a12, a22; ///< sum of w n n^T
    T b0, b1, b2;                   ///< sum of w d n
    T c;                            ///< sum of w d^2
    T w;                            ///< sum of w (the area)

    /// The plane through p with unit normal n, weighted by w (a triangle's area).
    static BasicQuadric plane(const Vec3d& n, const Vec3d& p, double w)
    {
        const double d = -n.dot(p);
        BasicQuadric q{};
        q.a00 = w * n[0] * n[0], q.a01 = w * n[0] * n[1], q.a02 = w * n[0] * n[2];
        q.a11 = w * n[1] * n[1], q.a12 = w * n[1] * n[2], q.a22 = w * n[2] * n[2];
        q.b0 = w * d * n[0], q.b1 = w * d * n[1], q.b2 = w * d * n[2];
        q.c = w * d * d, q.w = w;
        return q;
    }

    FLUIDSURF_QUADRIC_INLINE BasicQuadric& operator+=(const BasicQuadric& o)
    {
        a00 += o.a00, a01 += o.a01, a02 += o.a02, a11 += o.a11, a12 += o.a12, a22 += o.a22;
        b0 += o.b0, b1 += o.b1, b2 += o.b2, c += o.c, w += o.w;
        return *this;
    }
    FLUIDSURF_QUADRIC_INLINE BasicQuadric operator+(const BasicQuadric& o) const
    {
        return BasicQuadric(*this) += o;
    }

    /// The same planes with the origin moved to d: the quadric of x -> (this)(x + d).
    FLUIDSURF_QUADRIC_INLINE BasicQuadric movedTo(T d0, T d1, T d2) const
    {
        BasicQuadric q = *this; // A stays; b becomes A d + b, c the error at d
        q.b0 = a00 * d0 + a01 * d1 + a02 * d2 + b0;
        q.b1 = a01 * d0 + a11 * d1 + a12 * d2 + b1;
        q.b2 = a02 * d0 + a12 * d1 + a22 * d2 + b2;
        q.c = error(d0, d1, d2);
        return q;
    }
    BasicQuadric movedTo(const Vec3d& d) const { return movedTo(d[0], d[1], d[2]); }

    /// Weighted sum of squared distances from (x, y, z) to the planes.
    FLUIDSURF_QUADRIC_INLINE T error(T x, T y, T z) const
    {
        const T e = x * (a00 * x + 2 * a01 * y + 2 * a02 * z) + y * (a11 * y + 2 * a12 * z) +
                    a22 * z * z + 2 * (b0 * x + b1 * y + b2 * z) + c;
        return e > 0 ? e : T{}; // rounding can take a zero error below 0
    }
    double error(const Vec3d& p) const { return error(p[0], p[1], p[2]); }

    /// The point of least error (into x), pulled towards `rest` along the directions the planes
    /// leave free: on a flat patch every point of the plane has the same error, and the plain
    /// minimum is then undefined (a singular matrix) or, with a little noise, far away along
    /// the plane. The pull, 1e-3 of the planes' weight, decides only such directions.
    FLUIDSURF_QUADRIC_INLINE void minimizer(const T (&rest)[3], T (&x)[3]) const
    {
        const T eps = 1e-3 * (a00 + a11 + a22);
        const T m00 = a00 + eps, m11 = a11 + eps, m22 = a22 + eps;
        const T r0 = eps * rest[0] - b0, r1 = eps * rest[1] - b1, r2 = eps * rest[2] - b2;
        // Cramer's rule on the symmetric positive definite matrix
        const T c00 = m11 * m22 - a12 * a12, c01 = a02 * a12 - a01 * m22,
                c02 = a01 * a12 - a02 * m11;
        const T det = m00 * c00 + a01 * c01 + a02 * c02;
        const T c11 = m00 * m22 - a02 * a02, c12 = a01 * a02 - m00 * a12,
                c22 = m00 * m11 - a01 * a01;
        const T inv = 1 / det; // one division: the decimation's hottest line
        // (no planes, or a matrix no better than singular: the rest point)
        const auto solved = (eps > 0) & (det > 0);
        x[0] = solved ? (c00 * r0 + c01 * r1 + c02 * r2) * inv : rest[0];
        x[1] = solved ? (c01 * r0 + c11 * r1 + c12 * r2) * inv : rest[1];
        x[2] = solved ? (c02 * r0 + c12 * r1 + c22 * r2) * inv : rest[2];
    }
    Vec3d minimizer(const Vec3d& rest) const
    {
        const double r[3] = {rest[0], rest[1], rest[2]};
        double x[3];
        minimizer(r, x);
        return Vec3d(x[0], x[1], x[2]);
    }
};

using Quadric = BasicQuadric<double>;

/// A quadric kept in 44 bytes instead of 88, for one a vertex: floats, per unit of weight
/// (means of n n^T, d n and d^2, so that no scene's scale leaves float's range) and relative
/// to the vertex's own point (so that d is a fraction of an edge, not a distance across the
/// scene: floats' 7 digits then hold the errors that decide the collapses to about 1e-6).
struct PackedQuadric
{
    float w;
    float a00, a01, a02, a11, a12, a22, b0, b1, b2, c;

    /// q, whose origin is the vertex's point.
    static PackedQuadric pack(const Quadric& q)
    {
        const double s = q.w > 0 ? 1 / q.w : 0;
        return {float(q.w),       float(q.a00 * s), float(q.a01 * s), float(q.a02 * s),
                float(q.a11 * s), float(q.a12 * s), float(q.a22 * s), float(q.b0 * s),
                float(q.b1 * s),  float(q.b2 * s),  float(q.c * s)};
    }
    /// The quadric, its origin the vertex's point.
    Quadric unpack() const
    {
        const double s = w;
        return {a00 * s, a01 * s, a02 * s, a11 * s, a12 * s, a22 * s,
                b0 * s,  b1 * s,  b2 * s,  c * s,   s};
    }
};

} // namespace post
} // namespace fluidsurf
