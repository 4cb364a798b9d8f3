// TriangleDistance.h - the exact distance from a point to a triangle (or a segment), shared by
// meshDistance and the decimation's guard on how far a collapse moves the surface; and the
// nearest point itself, for the step that covers the particles a surface misses.
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

/// The point of triangle (a, b, c) nearest p, as barycentric weights of a, b and c (Ericson,
/// Real-Time Collision Detection, 5.1.5: p's region among the corners, sides and face).
inline Vec3d nearestOnTriangle(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c)
{
    const Vec3d ab = b - a, ac = c - a, ap = p - a;
    const double d1 = ab.dot(ap), d2 = ac.dot(ap);
    if (d1 <= 0 && d2 <= 0) return {1, 0, 0};
    const Vec3d bp = p - b;
    const double d3 = ab.dot(bp), d4 = ac.dot(bp);
    if (d3 >= 0 && d4 <= d3) return {0, 1, 0};
    const double vc = d1 * d4 - d3 * d2;
    if (vc <= 0 && d1 >= 0 && d3 <= 0) {
        const double v = d1 / (d1 - d3);
        return {1 - v, v, 0};
    }
    const Vec3d cp = p - c;
    const double d5 = ab.dot(cp), d6 = ac.dot(cp);
    if (d6 >= 0 && d5 <= d6) return {0, 0, 1};
    const double vb = d5 * d2 - d1 * d6;
    if (vb <= 0 && d2 >= 0 && d6 <= 0) {
        const double w = d2 / (d2 - d6);
        return {1 - w, 0, w};
    }
    const double va = d3 * d6 - d5 * d4;
    if (va <= 0 && (d4 - d3) >= 0 && (d5 - d6) >= 0) {
        const double w = (d4 - d3) / ((d4 - d3) + (d5 - d6));
        return {0, 1 - w, w};
    }
    const double sum = va + vb + vc;
    if (!(sum > 0)) return {1, 0, 0}; // degenerate: a corner will do
    const double v = vb / sum, w = vc / sum;
    return {1 - v - w, v, w};
}

/// A triangle set up for many questions "is p within a distance of it?" (the decimation's step
/// guard asks each of its fans dozens): its plane and its barycentric solve are prepared once,
/// so that a question costs a few dot products where the point projects inside, as a rule.
class NearTriangle
{
public:
    NearTriangle() = default;
    NearTriangle(const Vec3d& a, const Vec3d& b, const Vec3d& c)
        : mA(a), mE0(b - a), mE1(c - a), mN(mE0.cross(mE1))
    {
        mD00 = mE0.lengthSqr(), mD01 = mE0.dot(mE1), mD11 = mE1.lengthSqr();
        mN2 = mN.lengthSqr(); // = mD00 mD11 - mD01^2, the barycentric solve's determinant
    }

    /// (b - a) x (c - a): the normal, twice the area long
    const Vec3d& normal() const { return mN; }

    /// triangleDistance(p, a, b, c) <= sqrt(bound2), with squares and early outs: far from
    /// the plane means far from the triangle, and any near side will do.
    bool within(const Vec3d& p, double bound2) const
    {
        const Vec3d w = p - mA;
        if (mN2 > 0) {
            const double h = w.dot(mN);
            if (h * h > bound2 * mN2) return false;
            const double d0 = w.dot(mE0), d1 = w.dot(mE1); // the projection's, as well
            const double u = mD11 * d0 - mD01 * d1, v = mD00 * d1 - mD01 * d0;
            if (u >= 0 && v >= 0 && u + v <= mN2) return true;
        }
        auto side2 = [&](const Vec3d& from, const Vec3d& along) { // w relative to `from`
            const double len2 = along.lengthSqr();
            const double t = len2 > 0 ? std::clamp(from.dot(along) / len2, 0.0, 1.0) : 0.0;
            return (from - along * t).lengthSqr();
        };
        return side2(w, mE0) <= bound2 || side2(w, mE1) <= bound2 ||
               side2(w - mE0, mE1 - mE0) <= bound2;
    }

private:
    Vec3d mA{0.0}, mE0{0.0}, mE1{0.0}, mN{0.0};
    double mD00 = 0, mD01 = 0, mD11 = 0, mN2 = 0;
};

/// triangleDistance(p, a, b, c) <= bound, for one question (see NearTriangle for many).
inline bool withinDistance(const Vec3d& p, const Vec3d& a, const Vec3d& b, const Vec3d& c,
                           double bound)
{
    return NearTriangle(a, b, c).within(p, bound * bound);
}

} // namespace fluidsurf
