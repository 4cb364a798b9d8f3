// FieldMath.h - the last step of the field at one vertex: from the kernel sums to phi (the
// closed-form symmetric 3x3 eigenvalue in double, the SSP07 factor f, the clamp). Plain C++ that
// nvcc also compiles for the device (FLUIDSURF_HD), so the CPU and CUDA backends share one
// formula; no OpenVDB, no Params here.
#pragma once

#include "util/HostDevice.h"

#include <math.h>

namespace fluidsurf {
namespace field {

struct FieldSums
{
    double w = 0;
    double d[3] = {0, 0, 0};
    double r = 0; ///< sum w_j r_j (per-particle radii only)
    double g[3] = {0, 0, 0};
    double m[6] = {0, 0, 0, 0, 0, 0}; ///< xx, xy, xz, yy, yz, zz
};

struct FieldConstants
{
    double influenceRadius = 0;
    double radius = 0;      ///< uniform r (used when perParticleRadii is false)
    double radiusScale = 1; ///< rbar's factor (Params::radiusScale)
    bool perParticleRadii = false;
    bool ssp07 = true;
    /// [YT10]'s density field: phi = (isoLevel - the r-sum) R, where each kernel's radius slot
    /// carries V_j W's factor (field/AnisotropicField.h)
    bool density = false;
    double isoLevel = 0.5;
    double tLow = 0.4, tHigh = 3.5;
    float background = 0; ///< phi is clamped to [-background, background]
};

/// v clamped to [lo, hi]; NaN gives lo (as fmin(fmax(v, lo), hi) does). Comparisons, not
/// fmin/fmax: on the host those are library calls (2% of a reconstruction).
FLUIDSURF_HD inline double clampTo(double v, double lo, double hi)
{
    return !(v >= lo) ? lo : v > hi ? hi : v;
}

/// The larger of a and b, as a comparison (see clampTo).
FLUIDSURF_HD inline double maxOf(double a, double b)
{
    return a >= b ? a : b;
}

/// The operations beyond + - * / and comparisons that the eigenvalue needs, on doubles (host
/// and device). FieldValueWide.cc has the same on four doubles a register, so that both run the
/// one formula below, op for op.
struct ScalarOps
{
    FLUIDSURF_HD static double root(double v) { return sqrt(v); }
    FLUIDSURF_HD static double clamp(double v, double lo, double hi) { return clampTo(v, lo, hi); }
    FLUIDSURF_HD static double select(bool m, double a, double b) { return m ? a : b; }
};

// Always inlined: into FieldValueWide's AVX2 function too, where a call would run without AVX.
#ifdef __CUDACC__
#define FLUIDSURF_FIELD_INLINE __forceinline__
#else
#define FLUIDSURF_FIELD_INLINE __attribute__((always_inline)) inline
#endif

/// cos(acos(h) / 3) for h in [-1, 1], the largest root c of 4 c^3 - 3 c = h, without acos and
/// cos (a sixth of the field stage's time on the host, and 8% of it saved). With u = sqrt((1 + h) /
/// 2) and d = 2 c - 1 the root solves d sqrt(d + 3) = 2 u, an equation whose slope is at least
/// sqrt(3) everywhere (in c, two roots meet at h = -1): a quartic in u (within 6e-5) and two Newton
/// steps give d to 1e-15.
template <typename Ops = ScalarOps, typename T>
FLUIDSURF_HD FLUIDSURF_FIELD_INLINE T cosThirdOfAcos(T h)
{
    const T u = Ops::root((1 + h) * 0.5);
    T d = (((-0.0175 * u + 0.07666) * u - 0.2127) * u + 1.1535) * u;
    for (int step = 0; step < 2; ++step) {
        const T s = Ops::root(d + 3);
        d -= 2 * s * (d * s - 2 * u) / (3 * d + 6);
    }
    return (1 + d) * 0.5;
}

/// Largest eigenvalue of the symmetric 3x3 matrix (xx, xy, xz, yy, yz, zz).
template <typename Ops = ScalarOps, typename T>
FLUIDSURF_HD FLUIDSURF_FIELD_INLINE T largestEigenvalueSym(const T a[6])
{
    const T p1 = a[1] * a[1] + a[2] * a[2] + a[4] * a[4];
    const T q = (a[0] + a[3] + a[5]) / 3;
    const T b0 = a[0] - q, b3 = a[3] - q, b5 = a[5] - q;
    const T p2 = b0 * b0 + b3 * b3 + b5 * b5 + 2 * p1;
    const T p = Ops::root(p2 / 6);
    // det((A - qI) / p) / 2, clamped against rounding (and 0 / 0 where p is 0, below)
    const T det = b0 * (b3 * b5 - a[4] * a[4]) - a[1] * (a[1] * b5 - a[4] * a[2]) +
                  a[2] * (a[1] * a[4] - b3 * a[2]);
    const T half = Ops::clamp(det / (2 * p * p * p), -1.0, 1.0);
    // q alone for a multiple of the identity (a select, not a branch: the same on 4 lanes)
    return Ops::select(p2 > 1e-30 * (q * q + 1e-300), q + 2 * p * cosThirdOfAcos<Ops>(half), q);
}

/// phi at a vertex from its sums; +background when no particle is within R (SSP07, ZB05).
FLUIDSURF_HD inline float fieldValue(const FieldSums& s, const FieldConstants& c)
{
    if (c.density)
        return float(clampTo((c.isoLevel - s.r) * c.influenceRadius, -double(c.background),
                             double(c.background)));
    if (!(s.w > 0)) return c.background;
    const double inv = 1 / s.w;
    const double xb[3] = {s.d[0] * inv, s.d[1] * inv, s.d[2] * inv};
    const double dist = sqrt(xb[0] * xb[0] + xb[1] * xb[1] + xb[2] * xb[2]);
    const double rbar = (c.perParticleRadii ? s.r * inv : c.radius) * c.radiusScale;
    double f = 1;
    if (c.ssp07) {
        const double k = 6 / (c.influenceRadius * c.influenceRadius) * inv;
        // Symmetric part of J = k (M - xb G^T).
        const double sym[6] = {
            k * (s.m[0] - xb[0] * s.g[0]),
            k * (s.m[1] - 0.5 * (xb[0] * s.g[1] + xb[1] * s.g[0])),
            k * (s.m[2] - 0.5 * (xb[0] * s.g[2] + xb[2] * s.g[0])),
            k * (s.m[3] - xb[1] * s.g[1]),
            k * (s.m[4] - 0.5 * (xb[1] * s.g[2] + xb[2] * s.g[1])),
            k * (s.m[5] - xb[2] * s.g[2]),
        };
        // Gershgorin bound: when every disc lies below t_low, f = 1 without the eigen-solve.
        const double bound =
            maxOf(maxOf(sym[0] + fabs(sym[1]) + fabs(sym[2]), sym[3] + fabs(sym[1]) + fabs(sym[4])),
                  sym[5] + fabs(sym[2]) + fabs(sym[4]));
        if (bound >= c.tLow) {
            const double ev = largestEigenvalueSym(sym);
            if (ev >= c.tLow) {
                const double gamma = clampTo((c.tHigh - ev) / (c.tHigh - c.tLow), 0.0, 1.0);
                f = gamma * gamma * gamma - 3 * gamma * gamma + 3 * gamma;
            }
        }
    }
    const double phi = dist - rbar * f;
    return float(clampTo(phi, -double(c.background), double(c.background)));
}

} // namespace field
} // namespace fluidsurf
