// SmoothTest.cc - bounded smoothing along the normals (post/Smooth): a bumpy sphere comes out
// rounder with no point moved past the bound, a spike is held at the bound, open borders stay,
// and the same bits come out for any thread count.
#include "post/Smooth.h"
#include "post/IsolatedSpheres.h"

#include <fluidsurf/MeshCheck.h>

#include <tbb/global_control.h>

#include <gtest/gtest.h>

#include <cmath>

namespace fluidsurf {
namespace {

double length(const Vec3f& v)
{
    return std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
}

/// The unit icosphere of level 4 with every point pushed out or in by up to `bump` (a fixed
/// hash of its index, not a random generator: the same mesh everywhere).
TriangleMesh bumpySphere(double bump)
{
    TriangleMesh m = post::unitIcosphere(4);
    for (size_t v = 0; v < m.points.size(); ++v) {
        const double u = double((v * 2654435761u) % 1000) / 999.0; // in [0, 1]
        m.points[v] = m.points[v] * float(1 + bump * (2 * u - 1));
    }
    return m;
}

double radiusSpread(const TriangleMesh& m)
{
    double sum = 0, sum2 = 0;
    for (const Vec3f& p : m.points)
        sum += length(p), sum2 += length(p) * length(p);
    const double n = double(m.points.size()), mean = sum / n;
    return std::sqrt(std::max(0.0, sum2 / n - mean * mean));
}

TEST(Smooth, BumpySphereComesOutRounderWithinTheBound)
{
    const TriangleMesh bumpy = bumpySphere(0.02);
    const double bound = 0.03;
    const TriangleMesh s = post::smoothAlongNormals(bumpy, 6, bound);
    ASSERT_EQ(s.points.size(), bumpy.points.size());
    EXPECT_EQ(s.triangles, bumpy.triangles);
    EXPECT_LT(radiusSpread(s), 0.5 * radiusSpread(bumpy)); // 36% here
    for (size_t v = 0; v < s.points.size(); ++v)
        ASSERT_LE(length(s.points[v] - bumpy.points[v]), bound + 1e-6) << v;
    const MeshReport before = checkMesh(bumpy), after = checkMesh(s);
    EXPECT_TRUE(after.watertight()) << describe(after);
    EXPECT_NEAR(after.volume, before.volume, 0.01 * before.volume);
    EXPECT_TRUE(s.normals.empty()); // moved points: the old normals would be stale
    // no rounds, or no room to move: the mesh as it was
    EXPECT_EQ(post::smoothAlongNormals(bumpy, 0, bound).points, bumpy.points);
    EXPECT_EQ(post::smoothAlongNormals(bumpy, 6, 0.0).points, bumpy.points);
}

TEST(Smooth, SpikeIsHeldAtTheBound)
{
    TriangleMesh spiky = post::unitIcosphere(3);
    spiky.points[0] = spiky.points[0] * 1.5f; // a tip half a radius out
    const double bound = 0.05;
    const TriangleMesh free = post::smoothAlongNormals(spiky, 6, 10.0);
    const TriangleMesh held = post::smoothAlongNormals(spiky, 6, bound);
    // unbounded, the tip is pulled well in; bounded, it moves exactly the bound
    EXPECT_GT(length(free.points[0] - spiky.points[0]), 4 * bound);
    EXPECT_NEAR(length(held.points[0] - spiky.points[0]), bound, 1e-6);
    EXPECT_GT(length(held.points[0]), 1.4);
}

TEST(Smooth, OpenBorderStaysAndTheInsideFlattens)
{
    // a 16 x 16 grid of unit squares in z = 0 with its inner points raised or lowered by 0.1
    const uint32_t n = 16;
    TriangleMesh m;
    for (uint32_t j = 0; j <= n; ++j)
        for (uint32_t i = 0; i <= n; ++i) {
            const bool border = i == 0 || j == 0 || i == n || j == n;
            m.points.emplace_back(float(i), float(j), border ? 0.f : (i + j) % 2 ? 0.1f : -0.1f);
        }
    for (uint32_t j = 0; j < n; ++j)
        for (uint32_t i = 0; i < n; ++i) {
            const uint32_t a = j * (n + 1) + i;
            m.triangles.push_back({a, a + 1, a + n + 2});
            m.triangles.push_back({a, a + n + 2, a + n + 1});
        }
    const TriangleMesh s = post::smoothAlongNormals(m, 6, 0.5);
    double before = 0, after = 0;
    for (uint32_t j = 0; j <= n; ++j)
        for (uint32_t i = 0; i <= n; ++i) {
            const uint32_t v = j * (n + 1) + i;
            if (i == 0 || j == 0 || i == n || j == n) {
                EXPECT_EQ(s.points[v], m.points[v]) << i << "," << j;
                continue;
            }
            before += double(m.points[v].z) * m.points[v].z;
            after += double(s.points[v].z) * s.points[v].z;
            // along the normal: a flat patch's normal is z, so x and y stay
            EXPECT_NEAR(s.points[v].x, m.points[v].x, 0.02);
            EXPECT_NEAR(s.points[v].y, m.points[v].y, 0.02);
        }
    EXPECT_LT(after, 0.1 * before);
}

TEST(Smooth, SameBitsForAnyThreadCount)
{
    const TriangleMesh bumpy = bumpySphere(0.05);
    TriangleMesh one;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = post::smoothAlongNormals(bumpy, 6, 0.03);
    }
    const TriangleMesh many = post::smoothAlongNormals(bumpy, 6, 0.03);
    EXPECT_EQ(one.points, many.points);
}

} // namespace
} // namespace fluidsurf
