// ShapeGuard.cc - see ShapeGuard.h. The lane types never cross a call (check() is inlined into
// the functions compiled for its target), so GCC's note that their ABI differs without AVX does
// not apply.
#pragma GCC diagnostic ignored "-Wpsabi"

#include "post/ShapeGuard.h"

#include "util/Lanes.h"

#include <fluidsurf/Error.h>

#include <algorithm>
#include <cstring>

namespace fluidsurf {
namespace post {
namespace {

/// std::min({a, b, c}) on each lane: the first of the smallest.
template <typename V> __attribute__((always_inline)) inline V shortest(V a, V b, V c)
{
    const V m = b < a ? b : a;
    return c < m ? c : m;
}

/// Whether any lane of a compare's mask is set.
template <typename V, typename M> __attribute__((always_inline)) inline bool anyOf(M mask)
{
    long long any = 0;
    for (size_t l = 0; l < sizeof(V) / sizeof(double); ++l)
        any |= mask[l];
    return any != 0;
}

/// Whether triangles [first, first + the lanes of V) all keep their shapes with the moving
/// corner at q: keepsOne's operations, in its order, on each lane. V: util::Doubles or
/// util::WideDoubles.
template <typename V>
__attribute__((always_inline)) inline bool check(const double* data, size_t stride, size_t first,
                                                 const Vec3d& q)
{
    auto load = [&](int k) {
        V v;
        std::memcpy(&v, &data[k * stride + first], sizeof v);
        return v;
    };
    using G = ShapeGuard;
    const V ux = load(G::Ux), uy = load(G::Uy), uz = load(G::Uz);
    const V wx = load(G::Wx), wy = load(G::Wy), wz = load(G::Wz);
    const V nx = load(G::Nx), ny = load(G::Ny), nz = load(G::Nz);
    const V ax = ux - q[0], ay = uy - q[1], az = uz - q[2]; // u - q
    const V bx = wx - q[0], by = wy - q[1], bz = wz - q[2]; // w - q
    const V n1x = ay * bz - az * by, n1y = az * bx - ax * bz, n1z = ax * by - ay * bx;
    const V turn = nx * n1x + ny * n1y + nz * n1z;
    const V l0 = nx * nx + ny * ny + nz * nz, l1 = n1x * n1x + n1y * n1y + n1z * n1z;
    auto fail = ~(l1 > 0.0) | (turn < 0.0) | (turn * turn < kMaxTurnCos2 * l0 * l1);
    const V ex = ux - wx, ey = uy - wy, ez = uz - wz; // u - w
    const V uw = ex * ex + ey * ey + ez * ez;
    const V uq = ax * ax + ay * ay + az * az, wq = bx * bx + by * by + bz * bz;
    const V sides1 = uw * uq * wq;
    const V ls = l1 * shortest(uw, uq, wq);
    const auto thin = ls < kThinSin2 * sides1;
    if (!anyOf<V>(thin)) return !anyOf<V>(fail); // as a rule
    // an angle under kThinAngleDegrees, smaller than it was: the old shape too
    const V xx = load(G::Xx), xy = load(G::Xy), xz = load(G::Xz);
    const V cx = ux - xx, cy = uy - xy, cz = uz - xz, dx = wx - xx, dy = wy - xy, dz = wz - xz;
    const V ux2 = cx * cx + cy * cy + cz * cz, wx2 = dx * dx + dy * dy + dz * dz;
    const V sides0 = uw * ux2 * wx2;
    fail |= thin & (ls * sides0 < l0 * shortest(uw, ux2, wx2) * sides1);
    return !anyOf<V>(fail);
}

__attribute__((target("avx2"))) bool wideKeeps(const double* data, size_t stride, size_t n,
                                               const Vec3d& q)
{
    for (size_t i = 0; i < n; i += 4)
        if (!check<util::WideDoubles>(data, stride, i, q)) return false;
    return true;
}

bool narrowKeeps(const double* data, size_t stride, size_t n, const Vec3d& q)
{
    for (size_t i = 0; i < n; i += 2)
        if (!check<util::Doubles>(data, stride, i, q)) return false;
    return true;
}

} // namespace

int ShapeGuard::registerLanes()
{
    return util::doubleRegisterLanes();
}

void ShapeGuard::grow()
{
    const size_t stride = std::max<size_t>(64, 2 * mStride); // (fans of 60 without a copy)
    std::vector<double> data(kFields * stride);
    for (int k = 0; k < kFields; ++k)
        std::copy_n(&mData[k * mStride], mCount, &data[k * stride]);
    mData.swap(data);
    mStride = stride;
}

bool ShapeGuard::keeps(const Vec3d& q, int lanes)
{
    if (lanes != 2 && lanes != 4) throw ValueError("ShapeGuard: 2 or 4 doubles a register");
    if (lanes > registerLanes())
        throw ValueError("ShapeGuard: 4 doubles a register need a CPU with AVX2");
    return mCount == 0 || run(q, lanes);
}

bool ShapeGuard::run(const Vec3d& q, int lanes)
{
    if (mPadded != mCount) { // once for the points tried: the last register filled with
        mPadded = mCount;    // copies of the first triangle, the same verdict as its own
        for (size_t i = mCount; i % 4 != 0; ++i)
            for (int k = 0; k < kFields; ++k)
                mData[k * mStride + i] = mData[k * mStride];
    }
    return lanes == 4 ? wideKeeps(mData.data(), mStride, mCount, q)
                      : narrowKeeps(mData.data(), mStride, mCount, q);
}

} // namespace post
} // namespace fluidsurf
