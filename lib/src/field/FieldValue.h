// FieldValue.h - from the kernel sums at one grid vertex to the SSP07 / ZB05 value phi
// (DESIGN.md, "The SSP07 field"). Shared by the gather (narrow band, gather-full) and the scatter
// baseline, so all methods finish the field with the same arithmetic.
//
// With d_j = x_j - x (particle relative to the vertex), s_j = |d_j| / R, t_j = 1 - s_j^2 and
// w_j = t_j^3, the sums are
//   W = sum w_j, D = sum w_j d_j, Rs = sum w_j r_j, G = sum t_j^2 d_j, M = sum t_j^2 d_j d_j^T.
// Then xbar - x = D / W, rbar = Rs / W, grad w_j = 6 t_j^2 d_j / R^2, and
//   J = grad xbar = sum (x_j - xbar) grad w_j^T / W = (6 / R^2) (M - (D / W) G^T) / W.
// J is not symmetric. EV_max is the largest eigenvalue of its symmetric part (J + J^T) / 2,
// which is real, continuous in x, and bounds the real part of every eigenvalue of J from above
// (numerical range). It comes from the closed-form trigonometric solution of the 3x3 symmetric
// eigenproblem in double precision, its cos(acos(h) / 3) found as a cubic's root without
// trigonometry (FieldMath.h); the CUDA backend uses the same.
#pragma once

#include "field/FieldMath.h"
#include "util/Lanes.h"

#include <fluidsurf/Level.h>
#include <fluidsurf/Params.h>

#include <algorithm>
#include <cmath>

namespace fluidsurf {
namespace field {

/// The same sums while they are accumulated, in float (scatter: one vertex) or in
/// util::Lanes (gather: independent per-lane partial sums).
template <typename T> struct PartialSums
{
    T w{}, d0{}, d1{}, d2{}, r{}, g0{}, g1{}, g2{}, m0{}, m1{}, m2{}, m3{}, m4{}, m5{};
};

/// Add particle j at d = (ex, ey, ez) from the vertex, s2 = |d|^2 / R^2 (rj: its radius, used
/// with Radii). Particles at s2 >= 1 add exactly zero. The kernel for the scalar, 4-lane and
/// scatter paths; the 8-lane gather (GatherField.cc, wideSums) spells out the same steps with their
/// fused multiply-adds (FieldLanesTest checks it against std::fma).
template <bool Ssp07, bool Radii, typename T>
inline void addParticle(PartialSums<T>& a, T ex, T ey, T ez, T s2, T rj)
{
    // Particles within float rounding of R (t <= 1e-6, w <= 1e-18) count as outside: a lattice
    // particle exactly R away must not decide, by the rounding of leaf-local coordinates, whether
    // a vertex has a neighbour at all (phi jumps from the background to |x - p| - r there).
    T t = 1.f - s2;
    t = t > 1e-6f ? t : 0.f;
    const T t2 = t * t, wt = t2 * t;
    a.w += wt;
    a.d0 += wt * ex, a.d1 += wt * ey, a.d2 += wt * ez;
    if (Radii) a.r += wt * rj;
    if (Ssp07) {
        const T gx = t2 * ex, gy = t2 * ey, gz = t2 * ez;
        a.g0 += gx, a.g1 += gy, a.g2 += gz;
        a.m0 += gx * ex, a.m1 += gx * ey, a.m2 += gx * ez;
        a.m3 += gy * ey, a.m4 += gy * ez, a.m5 += gz * ez;
    }
}

inline double laneSum(float v)
{
    return v;
}
inline double laneSum(const util::Lanes& v)
{
    static_assert(util::kLanes == 4, "pairwise lane sum written for 4 lanes");
    return (v[0] + v[1]) + (v[2] + v[3]); // fixed order: deterministic; float like the lanes
}

inline double laneSum(const util::WideLanes& v)
{
    static_assert(util::kWideLanes == 8, "pairwise lane sum written for 8 lanes");
    return ((v[0] + v[1]) + (v[2] + v[3])) + ((v[4] + v[5]) + (v[6] + v[7]));
}

/// (always inlined: into the AVX2 sums too, where a call would run it without AVX)
template <typename T>
__attribute__((always_inline)) inline FieldSums toFieldSums(const PartialSums<T>& a)
{
    FieldSums s;
    s.w = laneSum(a.w), s.r = laneSum(a.r);
    s.d[0] = laneSum(a.d0), s.d[1] = laneSum(a.d1), s.d[2] = laneSum(a.d2);
    s.g[0] = laneSum(a.g0), s.g[1] = laneSum(a.g1), s.g[2] = laneSum(a.g2);
    s.m[0] = laneSum(a.m0), s.m[1] = laneSum(a.m1), s.m[2] = laneSum(a.m2);
    s.m[3] = laneSum(a.m3), s.m[4] = laneSum(a.m4), s.m[5] = laneSum(a.m5);
    return s;
}

/// [a0 + a1, a2 + a3, b0 + b1, b2 + b3, a4 + a5, a6 + a7, b4 + b5, b6 + b7]: AVX's hadd.
__attribute__((target("avx2,fma"), always_inline)) inline util::WideLanes
pairSums(util::WideLanes a, util::WideLanes b)
{
    return __builtin_shufflevector(a, b, 0, 2, 8, 10, 4, 6, 12, 14) +
           __builtin_shufflevector(a, b, 1, 3, 9, 11, 5, 7, 13, 15);
}

/// Lane i: the sum of v_i's lanes in laneSum's grouping, ((v0 + v1) + (v2 + v3)) + ((v4 + v5) +
/// (v6 + v7)), for eight registers at once (float addition is commutative: only the grouping
/// decides the bits).
__attribute__((target("avx2,fma"), always_inline)) inline util::WideLanes
laneSums(util::WideLanes v0, util::WideLanes v1, util::WideLanes v2, util::WideLanes v3,
         util::WideLanes v4, util::WideLanes v5, util::WideLanes v6, util::WideLanes v7)
{
    const util::WideLanes q0 = pairSums(pairSums(v0, v1), pairSums(v2, v3)); // halves of 0-3
    const util::WideLanes q1 = pairSums(pairSums(v4, v5), pairSums(v6, v7)); // and of 4-7
    return __builtin_shufflevector(q0, q1, 0, 1, 2, 3, 8, 9, 10, 11) +
           __builtin_shufflevector(q0, q1, 4, 5, 6, 7, 12, 13, 14, 15);
}

/// toFieldSums on 8 lanes, the same bits with an eighth of the adds: added one accumulator at
/// a time, a voxel's 14 lane sums took as many instructions as its particles (a tenth of the
/// field stage on the 1.7M-particle frame). Only for code compiled for AVX2, like wideSums
/// (GatherField.cc).
__attribute__((target("avx2,fma"), always_inline)) inline FieldSums
toFieldSumsWide(const PartialSums<util::WideLanes>& a)
{
    const util::WideLanes zero{};
    const util::WideLanes s = laneSums(a.w, a.d0, a.d1, a.d2, a.r, a.g0, a.g1, a.g2);
    const util::WideLanes m = laneSums(a.m0, a.m1, a.m2, a.m3, a.m4, a.m5, zero, zero);
    FieldSums f;
    f.w = s[0], f.d[0] = s[1], f.d[1] = s[2], f.d[2] = s[3], f.r = s[4];
    f.g[0] = s[5], f.g[1] = s[6], f.g[2] = s[7];
    for (int k = 0; k < 6; ++k)
        f.m[k] = m[k];
    return f;
}

/// FieldMath's constants from the parameters.
inline FieldConstants fieldConstants(const Params& p, const Level& level, bool perParticleRadii)
{
    FieldConstants c;
    c.influenceRadius = p.influenceRadius;
    c.radius = p.radius;
    c.radiusScale = p.radiusScale;
    c.perParticleRadii = perParticleRadii;
    c.ssp07 = p.field != FieldKind::Zb05; // Ssp07Aniso keeps the f-correction
    c.density = p.field == FieldKind::Yt10;
    c.isoLevel = p.isoLevel;
    c.tLow = p.tLow;
    c.tHigh = p.tHigh;
    c.background = float(p.background(level));
    return c;
}

} // namespace field
} // namespace fluidsurf
