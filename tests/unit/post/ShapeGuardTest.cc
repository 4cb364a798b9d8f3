// ShapeGuardTest.cc - decimation's shape guards on a collapse's whole fan (post/ShapeGuard, two
// or four triangles a register) against a reference written here, one triangle at a time in
// plain doubles from the rule itself: a triangle (x, u, w) whose corner x moves to q must not
// turn its normal by 60 degrees or more (nor fold or vanish), and must not get an angle under
// kThinAngleDegrees smaller than its smallest angle was. The verdict must be the same, on both
// register widths, for fans of every length (the last register filled up), with the failing
// triangle anywhere, and for the thin cases the sliver test decides.
#include "post/ShapeGuard.h"

#include <fluidsurf/Error.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <vector>

using fluidsurf::Vec3d;
using fluidsurf::post::ShapeGuard;

namespace {

struct Tri
{
    Vec3d x, u, w;
};

/// sin^2 of (x, u, w)'s smallest angle times its sides' product, and that product: the thin
/// test in squares, |n|^2 shortest^2 against a^2 b^2 c^2 (sin^2 = |n|^2 s^2 / (a^2 b^2 c^2)).
struct Thinness
{
    double l, shortest, sides;
};
Thinness thinness(const Vec3d& x, const Vec3d& u, const Vec3d& w)
{
    const double uw = (u - w).lengthSqr(), ux = (u - x).lengthSqr(), wx = (w - x).lengthSqr();
    return {(u - x).cross(w - x).lengthSqr(), std::min({uw, ux, wx}), uw * ux * wx};
}

/// One triangle, the rule as the guard's header states it, in doubles.
bool reference(const Tri& t, const Vec3d& q, bool* thinCase = nullptr)
{
    const Vec3d n0 = (t.u - t.x).cross(t.w - t.x), n1 = (t.u - q).cross(t.w - q);
    const double turn = n0.dot(n1), l0 = n0.lengthSqr(), l1 = n1.lengthSqr();
    const double cos2 = std::pow(std::cos(60 * M_PI / 180), 2);
    if (!(l1 > 0) || turn < 0 || turn * turn < cos2 * l0 * l1) return false;
    const Thinness now = thinness(q, t.u, t.w), was = thinness(t.x, t.u, t.w);
    const double thin2 = std::pow(std::sin(fluidsurf::kThinAngleDegrees * M_PI / 180), 2);
    if (!(now.l * now.shortest < thin2 * now.sides)) return true;
    if (thinCase) *thinCase = true;
    return !(now.l * now.shortest * was.sides < was.l * was.shortest * now.sides);
}

} // namespace

TEST(ShapeGuard, AFanKeepsItsShapesWhereEveryTriangleAloneDoes)
{
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1, 1);
    std::vector<int> widths{2};
    if (ShapeGuard::registerLanes() == 4) widths.push_back(4);
    ShapeGuard guard;
    size_t kept = 0, refused = 0, thinDecided = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        // every fill of the last register; now and then a fan past the first 60 triangles'
        // room (the guard grows, copying what it holds)
        const int n = trial % 50 == 0 ? 61 + int(rng() % 70) : 1 + int(rng() % 37);
        const Vec3d x(u(rng), u(rng), 0.1 * u(rng));
        std::vector<Tri> fan;
        guard.clear();
        for (int i = 0; i < n; ++i) {
            // a ring around x, some triangles of it slivers (w almost on the line from x to u)
            const double a = 2 * M_PI * i / n, b = 2 * M_PI * (i + 1) / n;
            Tri t{x, x + Vec3d(std::cos(a), std::sin(a), 0.2 * u(rng)),
                  x + Vec3d(std::cos(b), std::sin(b), 0.2 * u(rng))};
            if (rng() % 6 == 0)
                t.w = t.x + (t.u - t.x) * (0.5 + 0.4 * u(rng)) + Vec3d(0, 0, 1e-3 * u(rng));
            fan.push_back(t);
            guard.add(t.x, t.u, t.w, (t.u - t.x).cross(t.w - t.x));
        }
        // small moves keep most fans, large ones fold some; a few points far off
        const double reach = trial % 3 == 0 ? 0.05 : trial % 3 == 1 ? 0.5 : 2.0;
        const Vec3d q = x + Vec3d(u(rng), u(rng), 0.3 * u(rng)) * reach;
        bool expected = true, thin = false;
        for (const Tri& t : fan)
            expected = reference(t, q, &thin) && expected;
        thinDecided += thin;
        (expected ? kept : refused) += 1;
        for (int lanes : widths)
            ASSERT_EQ(guard.keeps(q, lanes), expected)
                << "trial " << trial << ", " << lanes << " lanes, " << n << " triangles";
        ASSERT_EQ(guard.keeps(q), expected);
    }
    EXPECT_GT(kept, 2000u);
    EXPECT_GT(refused, 2000u);
    EXPECT_GT(thinDecided, 500u); // the sliver test, not only the turn, decided many
}

TEST(ShapeGuard, OneBadTriangleAnywhereRefusesTheFan)
{
    // n wide triangles around x that a small move keeps, but for triangle k, whose far side
    // the move crosses (it flips): refused whatever k and n (k in the last register, filled up
    // with copies of the first, too); and kept without it.
    std::vector<int> widths{2};
    if (ShapeGuard::registerLanes() == 4) widths.push_back(4);
    ShapeGuard guard;
    const Vec3d x(0, 0, 0), q(0.01, 0.02, 0);
    for (int n = 1; n <= 13; ++n)
        for (int k = -1; k < n; ++k) { // k = -1: none bad
            guard.clear();
            for (int i = 0; i < n; ++i) {
                const double a = 2 * M_PI * i / n;
                Tri t{x, Vec3d(std::cos(a), std::sin(a), 0),
                      Vec3d(std::cos(a + 0.7), std::sin(a + 0.7), 0)};
                if (i == k) t.u = Vec3d(0.005, -1, 0), t.w = Vec3d(0.005, 1, 0);
                ASSERT_EQ(reference(t, q), i != k) << n << " " << k; // the fan is as meant
                guard.add(t.x, t.u, t.w, (t.u - t.x).cross(t.w - t.x));
            }
            for (int lanes : widths)
                EXPECT_EQ(guard.keeps(q, lanes), k < 0) << n << " " << k << " " << lanes;
        }
    guard.clear();
    EXPECT_TRUE(guard.keeps(Vec3d(5, 5, 5))); // no triangle: nothing to keep
}

TEST(ShapeGuard, RegisterWidthsOtherThanTwoOrFourAreRejected)
{
    ShapeGuard guard;
    EXPECT_THROW(guard.keeps(Vec3d(0, 0, 0), 3), fluidsurf::ValueError);
    if (ShapeGuard::registerLanes() == 2)
        EXPECT_THROW(guard.keeps(Vec3d(0, 0, 0), 4), fluidsurf::ValueError);
}
