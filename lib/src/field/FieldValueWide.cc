// FieldValueWide.cc - see FieldValueWide.h. Each line mirrors one of FieldMath.h's, in its
// order of operations; a lane that a branch there would skip computes anyway (dividing by zero
// at worst, without traps) and the select at the end drops it.
#include "field/FieldValueWide.h"

#include <immintrin.h>

namespace fluidsurf {
namespace field {

namespace {

typedef double D4 __attribute__((vector_size(32)));
typedef long long L4 __attribute__((vector_size(32)));

#define FLUIDSURF_AVX2 __attribute__((target("avx2")))

FLUIDSURF_AVX2 inline D4 root(D4 v)
{
    return _mm256_sqrt_pd(v);
}

FLUIDSURF_AVX2 inline D4 absolute(D4 v) // fabs: the sign bit cleared
{
    const L4 magnitude = L4{} + 0x7fffffffffffffffll;
    return (D4)((L4)v & magnitude);
}

FLUIDSURF_AVX2 inline D4 splat(double v)
{
    return D4{} + v;
}

/// clampTo: lo where !(v >= lo), else hi where v > hi, else v.
FLUIDSURF_AVX2 inline D4 clamp(D4 v, D4 lo, D4 hi)
{
    const D4 upper = v > hi ? hi : v;
    return v >= lo ? upper : lo;
}

FLUIDSURF_AVX2 inline D4 larger(D4 a, D4 b)
{
    return a >= b ? a : b;
}

FLUIDSURF_AVX2 inline D4 cosThirdOfAcos4(D4 h)
{
    const D4 u = root((1 + h) * 0.5);
    D4 d = (((-0.0175 * u + 0.07666) * u - 0.2127) * u + 1.1535) * u;
    for (int step = 0; step < 2; ++step) {
        const D4 s = root(d + 3);
        d -= 2 * s * (d * s - 2 * u) / (3 * d + 6);
    }
    return (1 + d) * 0.5;
}

FLUIDSURF_AVX2 inline D4 largestEigenvalue4(const D4 a[6])
{
    const D4 p1 = a[1] * a[1] + a[2] * a[2] + a[4] * a[4];
    const D4 q = (a[0] + a[3] + a[5]) / 3;
    const D4 b0 = a[0] - q, b3 = a[3] - q, b5 = a[5] - q;
    const D4 p2 = b0 * b0 + b3 * b3 + b5 * b5 + 2 * p1;
    const L4 identity = (p2 > 1e-30 * (q * q + 1e-300)) == 0; // a multiple of the identity
    const D4 p = root(p2 / 6);
    const D4 det = b0 * (b3 * b5 - a[4] * a[4]) - a[1] * (a[1] * b5 - a[4] * a[2]) +
                   a[2] * (a[1] * a[4] - b3 * a[2]);
    const D4 half = clamp(det / (2 * p * p * p), splat(-1.0), splat(1.0));
    const D4 ev = q + 2 * p * cosThirdOfAcos4(half);
    return identity ? q : ev;
}

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
    const D4 dist = root(xb[0] * xb[0] + xb[1] * xb[1] + xb[2] * xb[2]);
    const D4 rbar = c.perParticleRadii ? r * inv : splat(c.radius);
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
        const D4 ev = largestEigenvalue4(sym);
        const D4 gamma = clamp((c.tHigh - ev) / (c.tHigh - c.tLow), splat(0.0), splat(1.0));
        const D4 smooth = gamma * gamma * gamma - 3 * gamma * gamma + 3 * gamma;
        f = ((bound >= c.tLow) & (ev >= c.tLow)) ? smooth : f;
    }
    const D4 phi = dist - rbar * f;
    const double bg = double(c.background);
    const D4 value = clamp(phi, splat(-bg), splat(bg));
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
