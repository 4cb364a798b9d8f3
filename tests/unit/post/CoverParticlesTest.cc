// CoverParticlesTest.cc - the step that covers the particle centres a surface leaves outside
// (post/CoverParticles): on a sphere of radius ten voxels, centres half a voxel and nearly a voxel
// out end inside (ray parity, MeshInside.h) and at least half the margin from the surface (exact
// distances to every triangle), one inside by less than half the margin is pushed to it, one
// too far out is left; points out of every bump's reach keep their bits, no triangle turns by
// 60 degrees or more. Centres past the first batches are covered as well. A thin disc's far side
// stays where it was when a centre sits over its near side; the same bits for any thread count.
#include "post/CoverParticles.h"
#include "MeshInside.h"
#include "post/IsolatedSpheres.h"
#include "util/TriangleDistance.h"

#include <fluidsurf/MeshCheck.h>

#include <tbb/global_control.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

namespace fluidsurf {
namespace {

/// The unit icosphere of level 4 (edges about 0.066) scaled by (sx, sy, sz).
TriangleMesh ellipsoid(float sx, float sy, float sz)
{
    TriangleMesh m = post::unitIcosphere(4);
    for (Vec3f& p : m.points)
        p = Vec3f(p.x * sx, p.y * sy, p.z * sz);
    return m;
}

/// The exact distance from p to the mesh (every triangle).
double distanceTo(const TriangleMesh& m, const Vec3f& p)
{
    double best = 1e300;
    for (const auto& t : m.triangles)
        best = std::min(best, triangleDistance(toVec3d(p), toVec3d(m.points[t[0]]),
                                               toVec3d(m.points[t[1]]), toVec3d(m.points[t[2]])));
    return best;
}

post::CoverParams coverParams()
{
    post::CoverParams p; // the defaults of PostProcess.cc at a voxel of 1
    p.margin = 0.1, p.reach = 2.5, p.maxDepth = 1.0;
    return p;
}

/// Each triangle's normal after against before: the cosine of the angle it turned.
double leastCosine(const TriangleMesh& before, const TriangleMesh& after)
{
    double least = 1;
    for (const auto& t : before.triangles) {
        const Vec3d a = post::sideCross(before.points, t), b = post::sideCross(after.points, t);
        least = std::min(least, a.dot(b) / (a.length() * b.length()));
    }
    return least;
}

Vec3f along(Vec3f direction, float length)
{
    const float n = std::sqrt(direction.x * direction.x + direction.y * direction.y +
                              direction.z * direction.z);
    return direction * (length / n);
}

TEST(CoverParticles, CentresOutsideEndInsideAndNothingFarMoves)
{
    const TriangleMesh sphere = ellipsoid(10, 10, 10);
    // half a voxel out, 0.95 out, 0.03 in (less than half the margin), 0.5 in, 1.5 out
    const std::vector<Vec3f> centres{along({1, 0.2f, 0.1f}, 10.5f), along({-0.3f, 1, 0.2f}, 10.95f),
                                     along({0.1f, -0.2f, 1}, 9.97f), along({-1, -1, 0.3f}, 9.5f),
                                     along({0.2f, 0.3f, -1}, 11.5f)};
    TriangleMesh m = sphere;
    const post::VertexTriangles around(m);
    const post::CoverStats st = post::coverParticles(m, around, centres, coverParams());
    EXPECT_EQ(st.covered, 3u);
    EXPECT_EQ(st.left, 1u);
    EXPECT_EQ(test::insideMesh(m, centres), (std::vector<bool>{true, true, true, true, false}));
    for (int k : {0, 1, 2})
        EXPECT_GE(distanceTo(m, centres[k]), 0.05) << "centre " << k; // half the margin
    EXPECT_NEAR(distanceTo(m, centres[3]), distanceTo(sphere, centres[3]), 1e-6);
    // untouched beyond a bump's reach of its centre (2.5 + 1 + 0.1); moved at most twice a
    // bump's height near them
    for (size_t v = 0; v < m.points.size(); ++v) {
        double nearest = 1e300;
        for (int k : {0, 1, 2})
            nearest = std::min(nearest, toVec3d(sphere.points[v] - centres[k]).length());
        const double moved = toVec3d(m.points[v] - sphere.points[v]).length();
        if (nearest > 3.6) EXPECT_EQ(m.points[v], sphere.points[v]) << v;
        EXPECT_LE(moved, 2 * (0.95 + 0.1)) << v;
    }
    EXPECT_GT(leastCosine(sphere, m), 0.5);
    const MeshReport before = checkMesh(sphere), after = checkMesh(m);
    EXPECT_TRUE(after.watertight()) << describe(after);
    EXPECT_GT(after.volume, before.volume);
    EXPECT_LT(after.volume, 1.01 * before.volume);
}

TEST(CoverParticles, CentresAfterTheFirstBatchesAreCoveredToo)
{
    // the centres go 16,384 at a time (a bound on the memory of their patches): 40,000 far out,
    // then two to cover, one in the third batch
    const TriangleMesh sphere = ellipsoid(10, 10, 10);
    std::vector<Vec3f> centres(40000, Vec3f(100, 0, 0));
    centres[20000] = along({1, 0.2f, 0.1f}, 10.5f), centres.back() = along({0, 1, 0}, 10.4f);
    TriangleMesh m = sphere;
    const post::CoverStats st =
        post::coverParticles(m, post::VertexTriangles(m), centres, coverParams());
    EXPECT_EQ(st.covered, 2u);
    EXPECT_EQ(st.left, 39998u);
    const std::vector<bool> inside = test::insideMesh(m, {centres[20000], centres.back()});
    EXPECT_TRUE(inside[0] && inside[1]);
}

TEST(CoverParticles, AThinDiscsFarSideStays)
{
    // 4 voxels across, 1 thick: all of it within a bump's reach of a centre over its middle
    const TriangleMesh disc = ellipsoid(2, 2, 0.5);
    TriangleMesh m = disc;
    const post::VertexTriangles around(m);
    const std::vector<Vec3f> centre{Vec3f(0.1f, 0.05f, 0.9f)}; // 0.4 out
    EXPECT_EQ(post::coverParticles(m, around, centre, coverParams()).covered, 1u);
    EXPECT_TRUE(test::insideMesh(m, centre)[0]);
    size_t far = 0;
    for (size_t v = 0; v < m.points.size(); ++v) {
        if (!(disc.points[v].z < -0.1f)) continue;
        EXPECT_EQ(m.points[v], disc.points[v]) << v;
        ++far;
    }
    EXPECT_GT(far, 1000u);
    EXPECT_GT(leastCosine(disc, m), 0.5);
}

TEST(CoverParticles, SameBitsForAnyThreadCount)
{
    const TriangleMesh sphere = ellipsoid(10, 10, 10);
    std::vector<Vec3f> centres; // 200 of them, 0.1 to 0.9 out, some close enough to share
    for (uint32_t i = 0; i < 200; ++i) {
        const float u = float((i * 2654435761u) % 1000) / 999.f, w = float(i) / 199.f;
        const float z = 2 * w - 1, s = std::sqrt(1 - z * z), a = 40 * u;
        centres.push_back(along({s * std::cos(a), s * std::sin(a), z}, 10.1f + 0.8f * u));
    }
    TriangleMesh one = sphere, many = sphere;
    post::CoverStats a, b;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        a = post::coverParticles(one, post::VertexTriangles(one), centres, coverParams());
    }
    b = post::coverParticles(many, post::VertexTriangles(many), centres, coverParams());
    EXPECT_EQ(one.points, many.points);
    EXPECT_EQ(a.covered, b.covered);
    EXPECT_GT(a.covered, 150u);
    const std::vector<bool> inside = test::insideMesh(many, centres);
    EXPECT_LE(size_t(std::count(inside.begin(), inside.end(), false)), a.left);
}

} // namespace
} // namespace fluidsurf
