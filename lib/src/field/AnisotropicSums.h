// AnisotropicSums.h - one anisotropic kernel's terms of a voxel's field sums (AnisotropicField.h),
// written once for the host's AVX2 lanes, its scalar fallback and the CUDA gather: plain C++
// that nvcc also compiles (FLUIDSURF_HD), every fused multiply-add spelled out through Ops::fma,
// so the three give the same bits (the CUDA file is compiled with --fmad=false, the host's
// without contraction in this order of operations).
//
// A voxel's sums are added one kernel after another in a fixed order (the leaf's gather order),
// in float, each lane of a register a different voxel. A kernel that does not reach the voxel adds
// exact zeros (t is cut to 0, and x + 0 * y = x for the +0 the sums start from), so any superset
// of the kernels that reach it, in that order, gives the same bits: the host tests kernels against
// 2 x 2 x 2 voxel blocks, the device against single voxels, and the sums agree.
#pragma once

#include "field/FieldMath.h"
#include "util/HostDevice.h"

namespace fluidsurf {
namespace field {

/// The running sums of one voxel (or one voxel a lane): FieldSums' terms, with the off-diagonal
/// entries of M summed twice (d_a g_b + d_b g_a; halved in toSums).
template <typename T> struct AnisotropicAccumulator
{
    T w{}, d0{}, d1{}, d2{}, r{}, g0{}, g1{}, g2{}, m0{}, m1{}, m2{}, m3{}, m4{}, m5{};
};

/// One kernel, leaf-local: its centre c, its A' = R^2 G^2 (xx, xy, xz, yy, yz, zz; the identity
/// for the isotropic kernel) and its radius (with per-particle radii).
struct AnisotropicKernel
{
    float c[3];
    float a[6];
    float r;
};

/// Add kernel k's terms at voxel v (leaf-local), invR2 = 1 / R^2 (float):
///   d = c - v, A'd, s^2 = d.A'd / R^2, t = 1 - s^2 (0 where t <= 1e-6), w = t^3,
///   w += w, d += w d, r += w r_k, g += t^2 A'd, M += t^2 (d (A'd)^T + A'd d^T) off its diagonal.
template <typename Ops, bool Radii, typename T>
FLUIDSURF_HD FLUIDSURF_FIELD_INLINE void addKernel(AnisotropicAccumulator<T>& s, const T c[3],
                                                   const T a[6], T r, T vx, T vy, T vz, T invR2)
{
    const T ex = c[0] - vx, ey = c[1] - vy, ez = c[2] - vz;
    const T ax = Ops::fma(a[2], ez, Ops::fma(a[1], ey, a[0] * ex));
    const T ay = Ops::fma(a[4], ez, Ops::fma(a[3], ey, a[1] * ex));
    const T az = Ops::fma(a[5], ez, Ops::fma(a[4], ey, a[2] * ex));
    const T q = Ops::fma(ez, az, Ops::fma(ey, ay, ex * ax));
    const T t = Ops::cut(Ops::fnma(q, invR2, Ops::one()));
    if (Ops::none(t)) return; // (what follows would add exact zeros)
    const T t2 = t * t, wt = t2 * t;
    s.w = s.w + wt;
    s.d0 = Ops::fma(wt, ex, s.d0), s.d1 = Ops::fma(wt, ey, s.d1), s.d2 = Ops::fma(wt, ez, s.d2);
    if (Radii) s.r = Ops::fma(wt, r, s.r);
    const T gx = t2 * ax, gy = t2 * ay, gz = t2 * az;
    s.g0 = s.g0 + gx, s.g1 = s.g1 + gy, s.g2 = s.g2 + gz;
    s.m0 = Ops::fma(ex, gx, s.m0);
    s.m1 = Ops::fma(ey, gx, Ops::fma(ex, gy, s.m1));
    s.m2 = Ops::fma(ez, gx, Ops::fma(ex, gz, s.m2));
    s.m3 = Ops::fma(ey, gy, s.m3);
    s.m4 = Ops::fma(ez, gy, Ops::fma(ey, gz, s.m4));
    s.m5 = Ops::fma(ez, gz, s.m5);
}

/// The sums of lane values (float) as FieldSums (double; M's off-diagonal halved, exactly).
FLUIDSURF_HD inline FieldSums toSums(float w, float d0, float d1, float d2, float r, float g0,
                                     float g1, float g2, float m0, float m1, float m2, float m3,
                                     float m4, float m5)
{
    FieldSums s;
    s.w = w, s.r = r;
    s.d[0] = d0, s.d[1] = d1, s.d[2] = d2;
    s.g[0] = g0, s.g[1] = g1, s.g[2] = g2;
    s.m[0] = m0, s.m[1] = 0.5 * double(m1), s.m[2] = 0.5 * double(m2);
    s.m[3] = m3, s.m[4] = 0.5 * double(m4), s.m[5] = m5;
    return s;
}

/// addKernel's operations on one float: the host's fallback, and the CUDA gather's (fmaf is one
/// fused, correctly rounded operation on both, as AVX2's FMA is).
struct ScalarFloatOps
{
    FLUIDSURF_HD static float fma(float a, float b, float c) { return fmaf(a, b, c); }
    /// c - a b, one rounding
    FLUIDSURF_HD static float fnma(float a, float b, float c) { return fmaf(-a, b, c); }
    FLUIDSURF_HD static float one() { return 1.f; }
    /// addParticle's cut-off (FieldValue.h): within float rounding of R counts as outside
    FLUIDSURF_HD static float cut(float t) { return t > 1e-6f ? t : 0.f; }
    FLUIDSURF_HD static bool none(float t) { return t == 0.f; }
};

} // namespace field
} // namespace fluidsurf
