// ShapeGuard.h - decimation's shape guards for one collapse (DecimateBlock.h): whether moving an
// edge to a point keeps every triangle of its two fans that stays from folding (its normal
// turning by more than kMaxTurnDegrees) and from becoming a sliver (an angle under
// kThinAngleDegrees that was not already as thin).
//
// Why its own class: a collapse tries up to four points (the quadric's, the middle, either end),
// 1.9 on average on the 1.7M-particle frame, and each try walked both fans again, finding the
// same old normals, lengths and sides before the one thing that changes, the moved corner. Here
// the fans' triangles are set up once (add) and each point is checked on all of them at once,
// two or four triangles a register (keeps): the same operations, in the same order, as one
// triangle at a time in doubles, so each triangle's verdict is the same bit for bit (no FMA on
// either path).
#pragma once

#include "util/Vec3d.h"

#include <fluidsurf/MeshCheck.h>

#include <cmath>
#include <cstddef>
#include <vector>

namespace fluidsurf {
namespace post {

constexpr double kMaxTurnDegrees = 60; ///< the most a remaining triangle's normal may turn

inline const double kMaxTurnCos = std::cos(kMaxTurnDegrees * M_PI / 180);
inline const double kMaxTurnCos2 = kMaxTurnCos * kMaxTurnCos; ///< the turn guard compares squares
/// sin^2 of the smallest angle the thin guard lets a new triangle have: a triangle's smallest
/// angle (<= 60 deg) has sin^2 = |n|^2 shortest^2 / (a^2 b^2 c^2), |n| twice its area.
inline const double kThinSin2 = std::pow(std::sin(kThinAngleDegrees * M_PI / 180), 2);

class ShapeGuard
{
public:
    /// Doubles a register that keeps() uses by default: 4 where the CPU has AVX2, else 2.
    static int registerLanes();

    /// Forget the last collapse's triangles.
    void clear() { mCount = mPadded = 0; }
    /// A triangle that stays: (x, u, w) in its own turning order, its corner at x moving; n0 =
    /// (u - x) x (w - x), as the caller found it.
    void add(const Vec3d& x, const Vec3d& u, const Vec3d& w, const Vec3d& n0)
    {
        if (mCount + 4 >= mStride) grow();
        double* d = &mData[mCount++];
        const Vec3d* v[4] = {&u, &w, &n0, &x};
        for (int k = 0; k < 4; ++k)
            for (int a = 0; a < 3; ++a)
                d[(3 * k + a) * mStride] = (*v[k])[a];
    }
    /// Whether every triangle added keeps its shape with its moving corner at q, two or four
    /// triangles at a time (registerLanes()).
    bool keeps(const Vec3d& q) { return mCount == 0 || run(q, mLanes); }
    /// The same with `lanes` doubles a register: 2, or 4 where registerLanes() is 4 (tests run
    /// both); the verdict is the same either way.
    bool keeps(const Vec3d& q, int lanes);

    /// Per triangle, in lanes: u, w, n0 and x.
    enum Field { Ux, Uy, Uz, Wx, Wy, Wz, Nx, Ny, Nz, Xx, Xy, Xz, kFields };

private:
    /// Field k of triangle i at mData[k * mStride + i]; mStride: a multiple of 4 with room for
    /// one more register than the triangles (the copies that fill the last one).
    std::vector<double> mData;
    size_t mStride = 0, mCount = 0;
    size_t mPadded = 0; ///< mCount when the last register was filled (keeps)
    int mLanes = registerLanes();

    void grow();
    /// keeps() on a fan of at least one triangle.
    bool run(const Vec3d& q, int lanes);
};

} // namespace post
} // namespace fluidsurf
