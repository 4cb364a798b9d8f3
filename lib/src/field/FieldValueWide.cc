// FieldValueWide.cc - see FieldValueWide.h. The eigenvalue is FieldMath.h's own template, run
// with WideOps; the rest mirrors fieldValue line by line, in its order of operations. A lane
// that a branch there would skip computes anyway (dividing by zero at worst, without traps) and
// a select drops it.
// FieldMath's templates take and return 4-double registers here. They are always inlined into
// values4, which is compiled for AVX2, so no call passes one; GCC still warns at the template,
// which is compiled for the default target.
#pragma GCC diagnostic ignored "-Wpsabi"

#include "field/FieldValueWide.h"

#include <immintrin.h>

namespace fluidsurf {
namespace field {

namespace {

typedef double D4 __attribute__((vector_size(32)));
typedef long long L4 __attribute__((vector_size(32)));

#define FLUIDSURF_AVX2 __attribute__((target("avx2")))

FLUIDSURF_AVX2 inline D4 absolute(D4 v) // fabs: the sign bit cleared
{
    const L4 magnitude = L4{} + 0x7fffffffffffffffll;
    return (D4)((L4)v & magnitude);
}

FLUIDSURF_AVX2 inline D4 splat(double v)
{
    return D4{} + v;
}

FLUIDSURF_AVX2 inline D4 larger(D4 a, D4 b)
{
    return a >= b ? a : b;
}

/// FieldMath's ScalarOps on 4 lanes (for its cosThirdOfAcos and largestEigenvalueSym too).
struct WideOps
{
    FLUIDSURF_AVX2 static D4 root(D4 v) { return _mm256_sqrt_pd(v); }
    /// clampTo: lo where !(v >= lo), else hi where v > hi, else v.
    FLUIDSURF_AVX2 static D4 clamp(D4 v, double lo, double hi)
    {
        const D4 upper = v > hi ? splat(hi) : v;
        return v >= lo ? upper : splat(lo);
    }
    FLUIDSURF_AVX2 static D4 select(L4 m, D4 a, D4 b) { return m ? a : b; }
};

FLUIDSURF_AVX2 void values4(const FieldSums* s, const FieldConstants& c, float* out)
{
    D4 w, d[3], r, g[3], m[6];
    for (int l = 0; l < 4; ++l) {
        w[l] = s[l].w, r[l] = s[l].r;
        for (int k = 0; k < 3; ++k)
            d[k][l] = s[l].d[k], g[k][l] = s[l].g[k];
        for (int k = 0; k < 6; ++k)
            m[k][l] = s[l].m[k];
    }
    const D4 inv = 1 / w;
    const D4 xb[3] = {d[0] * inv, d[1] * inv, d[2] * inv};
    const D4 dist = WideOps::root(xb[0] * xb[0] + xb[1] * xb[1] + xb[2] * xb[2]);
    const D4 rbar = (c.perParticleRadii ? r * inv : splat(c.radius)) * splat(c.radiusScale);
    D4 f = splat(1.0);
    if (c.ssp07) {
        const D4 k = 6 / (c.influenceRadius * c.influenceRadius) * inv;
        const D4 sym[6] = {
            k * (m[0] - xb[0] * g[0]),
            k * (m[1] - 0.5 * (xb[0] * g[1] + xb[1] * g[0])),
            k * (m[2] - 0.5 * (xb[0] * g[2] + xb[2] * g[0])),
            k * (m[3] - xb[1] * g[1]),
            k * (m[4] - 0.5 * (xb[1] * g[2] + xb[2] * g[1])),
            k * (m[5] - xb[2] * g[2]),
        };
        const D4 bound = larger(larger(sym[0] + absolute(sym[1]) + absolute(sym[2]),
                                       sym[3] + absolute(sym[1]) + absolute(sym[4])),
                                sym[5] + absolute(sym[2]) + absolute(sym[4]));
        const D4 ev = largestEigenvalueSym<WideOps>(sym);
        const D4 gamma = WideOps::clamp((c.tHigh - ev) / (c.tHigh - c.tLow), 0.0, 1.0);
        const D4 smooth = gamma * gamma * gamma - 3 * gamma * gamma + 3 * gamma;
        f = ((bound >= c.tLow) & (ev >= c.tLow)) ? smooth : f;
    }
    const D4 phi = dist - rbar * f;
    const double bg = double(c.background);
    const D4 value = WideOps::clamp(phi, -bg, bg);
    for (int l = 0; l < 4; ++l)
        out[l] = w[l] > 0 ? float(value[l]) : c.background;
}

} // namespace

FLUIDSURF_AVX2 void fieldValuesWide(const FieldSums* sums, int n, const FieldConstants& c,
                                    float* out)
{
    for (int i = 0; i < n; i += 4) {
        if (n - i >= 4) {
            values4(sums + i, c, out + i);
            continue;
        }
        FieldSums last[4]; // the tail, padded with copies of its first voxel
        float values[4];
        for (int l = 0; l < 4; ++l)
            last[l] = sums[i + (i + l < n ? l : 0)];
        values4(last, c, values);
        for (int l = 0; i + l < n; ++l)
            out[i + l] = values[l];
    }
}

} // namespace field
} // namespace fluidsurf
