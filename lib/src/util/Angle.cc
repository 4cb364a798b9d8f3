// Angle.cc - see Angle.h. The lane types never cross a call (angleOf is inlined into the
// functions compiled for its target), so GCC's note that their ABI differs without AVX does not
// apply.
#pragma GCC diagnostic ignored "-Wpsabi"

#include "util/Angle.h"

#include "util/Lanes.h"

#include <fluidsurf/Error.h>

#include <cmath> // (M_PI and its kin)
#include <cstring>

namespace fluidsurf {
namespace util {
namespace {

/// atan(u) = u + u s Q(s), s = u^2, for |u| <= tan(pi / 8) (s <= 0.1716): Q's Taylor series
/// (-1/3 + s/5 - s^2/7 ...) economised to degree 10 by Chebyshev's polynomials on [0, 0.172],
/// in exact fractions, then rounded to doubles. Q's error is under 3.2e-17, so atan's under
/// 6e-18 of u: far below half an ulp. (Taylor's series itself needs 19 terms for that.)
constexpr double kQ[11] = {-0.3333333333333333,  0.1999999999999555,   -0.142857142846703,
                           0.1111111101539884,   -0.09090904578363243, 0.07692183084988473,
                           -0.06664508587737544, 0.05858113611572696,  -0.0508521650971275,
                           0.03922367097955391,  -0.019165732840266198};

/// atan2(y, x) lane by lane for y > 0: the smaller of y and |x| over the larger is t in
/// [0, 1]; above tan(pi / 8), atan(t) = pi / 4 + atan((t - 1) / (t + 1)), which is one
/// division of (small - big) by (small + big); then the octant. Selects, not branches, and no
/// FMA (neither target has it): the same operations on every lane whatever V is.
template <typename V> __attribute__((always_inline)) inline V angleOf(V y, V x)
{
    constexpr double kTanPi8 = 0.41421356237309504880;
    const V ax = x < 0 ? -x : x;
    const auto steep = y > ax;
    const V big = steep ? y : ax, small = steep ? ax : y;
    const auto high = small > kTanPi8 * big;
    const V u = (high ? small - big : small) / (high ? small + big : big);
    const V s = u * u;
    V q = V{} + kQ[10];
    for (int k = 9; k >= 0; --k)
        q = q * s + kQ[k];
    V r = u + u * s * q;
    r = high ? M_PI_4 + r : r;
    r = steep ? M_PI_2 - r : r;
    return x < 0 ? M_PI - r : r;
}

template <typename V>
__attribute__((always_inline)) inline void anglesIn(const double* y, const double* x, double* angle,
                                                    size_t n)
{
    constexpr size_t kWidth = sizeof(V) / sizeof(double);
    size_t i = 0;
    for (; i + kWidth <= n; i += kWidth) {
        V a, b;
        std::memcpy(&a, y + i, sizeof a), std::memcpy(&b, x + i, sizeof b);
        const V r = angleOf(a, b);
        std::memcpy(angle + i, &r, sizeof r);
    }
    if (i == n) return;
    V a, b; // the last few: the rest of the register y = x = 1 (any valid input)
    for (size_t l = 0; l < kWidth; ++l)
        a[l] = i + l < n ? y[i + l] : 1.0, b[l] = i + l < n ? x[i + l] : 1.0;
    const V r = angleOf(a, b);
    for (size_t l = 0; i + l < n; ++l)
        angle[i + l] = r[l];
}

__attribute__((target("avx2"))) void wideAngles(const double* y, const double* x, double* angle,
                                                size_t n)
{
    anglesIn<WideDoubles>(y, x, angle, n);
}

void narrowAngles(const double* y, const double* x, double* angle, size_t n)
{
    anglesIn<Doubles>(y, x, angle, n);
}

} // namespace

void angles(const double* y, const double* x, double* angle, size_t n, int lanes)
{
    if (lanes != 2 && lanes != 4) throw ValueError("angles: 2 or 4 doubles a register");
    if (lanes > doubleRegisterLanes())
        throw ValueError("angles: 4 doubles a register need a CPU with AVX2");
    lanes == 4 ? wideAngles(y, x, angle, n) : narrowAngles(y, x, angle, n);
}

void angles(const double* y, const double* x, double* angle, size_t n)
{
    angles(y, x, angle, n, doubleRegisterLanes());
}

} // namespace util
} // namespace fluidsurf
