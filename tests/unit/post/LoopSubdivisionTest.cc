// LoopSubdivisionTest.cc - one Loop step (post/LoopSubdivision): the icosahedron's new points
// where Loop's rules put them (worked out here from its geometry), flat patches stay flat with
// straight borders, a marching-cubes surface stays watertight and barely shrinks, and the same
// bits come out for any thread count.
#include "post/LoopSubdivision.h"
#include "post/IsolatedSpheres.h"

#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/MeshLevelSet.h>
#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Scenes.h>

#include <tbb/global_control.h>

#include <gtest/gtest.h>

#include <cmath>

namespace fluidsurf {
namespace {

double length(const Vec3f& v)
{
    return std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
}

TEST(LoopSubdivision, IcosahedronPointsWhereLoopsRulesPutThem)
{
    const TriangleMesh ico = post::unitIcosphere(0);
    const TriangleMesh s = post::loopSubdivide(ico);
    ASSERT_EQ(s.triangles.size(), 80u);
    ASSERT_EQ(s.points.size(), 12u + 30u); // a point per edge
    const MeshReport r = checkMesh(s);
    EXPECT_TRUE(r.watertight()) << describe(r);
    EXPECT_GT(r.volume, 0);
    // Old points: five neighbours, each at angle acos(1/sqrt5) from the point on the unit
    // sphere, so their sum is sqrt5 along it: |p'| = 1 - 5 beta + beta sqrt5.
    const double c = 3.0 / 8 + std::cos(2 * M_PI / 5) / 4, beta = (5.0 / 8 - c * c) / 5;
    for (size_t i = 0; i < 12; ++i)
        EXPECT_NEAR(length(s.points[i]), 1 - 5 * beta + beta * std::sqrt(5.0), 1e-6);
    // Edge points: 3/8 of the two ends (their sum has length 2cos(theta/2)), 1/8 of the two
    // opposite corners (at the same distance from the edge's middle on the other side): by
    // symmetry all along the edge's midpoint direction; checked against direct sums.
    for (size_t e = 12; e < s.points.size(); ++e) {
        const double len = length(s.points[e]);
        EXPECT_NEAR(len, length(s.points[12]), 1e-6); // all 30 alike
        EXPECT_LT(len, 1.0);
    }
    // one edge by hand: vertices 0 and 11 share triangles {0,11,5} and {0,10,11}
    Vec3f expected = (ico.points[0] + ico.points[11]) * (3.0f / 8) +
                     (ico.points[5] + ico.points[10]) * (1.0f / 8);
    bool found = false;
    for (size_t e = 12; e < s.points.size(); ++e)
        if (length(s.points[e] - expected) < 1e-6) found = true;
    EXPECT_TRUE(found);
}

TEST(LoopSubdivision, FlatPatchStaysFlatWithStraightBorders)
{
    // a 4 x 4 grid of squares in z = 0, each cut along its diagonal: an open patch
    TriangleMesh m;
    for (int j = 0; j <= 4; ++j)
        for (int i = 0; i <= 4; ++i)
            m.points.emplace_back(float(i), float(j), 0.f);
    for (uint32_t j = 0; j < 4; ++j)
        for (uint32_t i = 0; i < 4; ++i) {
            const uint32_t a = j * 5 + i;
            m.triangles.push_back({a, a + 1, a + 6});
            m.triangles.push_back({a, a + 6, a + 5});
        }
    const TriangleMesh s = post::loopSubdivide(m);
    const MeshReport r = checkMesh(s);
    EXPECT_EQ(r.nonManifoldEdges + r.misorientedEdges + r.degenerateTriangles, 0u) << describe(r);
    EXPECT_EQ(r.boundaryEdges, 2 * 16u); // each border edge halved
    for (size_t i = 0; i < s.points.size(); ++i)
        EXPECT_EQ(s.points[i].z, 0.f);
    EXPECT_TRUE(s.normals.empty()); // the chain's last step computes them (post/Normals.h)
    // the border follows its cubic B-spline, 3/4 p + 1/8 (two border neighbours): straight
    // stretches stay on their line, corners are rounded like the rest of it
    for (const Vec3f& p : s.points)
        EXPECT_TRUE(p.x >= 0 && p.x <= 4 && p.y >= 0 && p.y <= 4) << p.x << " " << p.y;
    EXPECT_EQ(s.points[2], Vec3f(2, 0, 0));
    EXPECT_EQ(s.points[10], Vec3f(0, 2, 0));
    EXPECT_EQ(s.points[0], Vec3f(0.125f, 0.125f, 0));
    EXPECT_EQ(s.points[24], Vec3f(3.875f, 3.875f, 0));
}

TEST(LoopSubdivision, SurfaceStaysWatertightAndThreadCountDoesNotMatter)
{
    SceneParams sp;
    sp.count = 20000;
    const ParticleSet ps = generateScene(Scene::Drop, sp);
    const RasterizeResult field = rasterizeParticles(ps, Params::fromRadius(sp.radius));
    const TriangleMesh raw = meshLevelSet(*field.grid);
    const TriangleMesh s = post::loopSubdivide(raw);
    EXPECT_EQ(s.triangles.size(), 4 * raw.triangles.size());
    const MeshReport before = checkMesh(raw), after = checkMesh(s);
    EXPECT_TRUE(after.watertight()) << describe(after);
    EXPECT_EQ(after.components, before.components);
    // Loop pulls a surface in where it curves: a little volume lost, never much
    EXPECT_LT(after.volume, before.volume);
    EXPECT_GT(after.volume, 0.98 * before.volume);
    TriangleMesh one;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        one = post::loopSubdivide(raw);
    }
    EXPECT_EQ(one.points, s.points);
    EXPECT_EQ(one.triangles, s.triangles);
}

TEST(LoopSubdivision, MoveBoundHoldsATipAndLeavesTheRestAlone)
{
    TriangleMesh spiky = post::unitIcosphere(2);
    spiky.points[0] = spiky.points[0] * 1.5f; // a tip half a radius out
    const double bound = 0.02;
    const TriangleMesh free = post::loopSubdivide(spiky);
    const TriangleMesh held = post::loopSubdivide(spiky, bound);
    ASSERT_EQ(held.triangles, free.triangles);
    // unbounded, the tip is pulled well in; bounded, by exactly the bound
    EXPECT_GT(length(free.points[0] - spiky.points[0]), 5 * bound);
    EXPECT_NEAR(length(held.points[0] - spiky.points[0]), bound, 1e-6);
    // every old point within the bound of where it was; where Loop moved it less, the same
    const size_t nv = spiky.points.size();
    size_t same = 0;
    for (size_t v = 0; v < nv; ++v) {
        EXPECT_LE(length(held.points[v] - spiky.points[v]), bound + 1e-6) << v;
        same += held.points[v] == free.points[v];
    }
    EXPECT_GT(same, nv / 2); // far from the tip the sphere's own moves are under the bound
    // every edge point within the bound of its edge's middle: each new point is the middle
    // of the two old points whose triangles' middle children it is a corner of
    for (size_t t = 0; t < spiky.triangles.size(); ++t) {
        const auto& [a, b, c] = spiky.triangles[t];
        const uint32_t ab = held.triangles[4 * t][1], ca = held.triangles[4 * t][2];
        EXPECT_LE(length(held.points[ab] - (spiky.points[a] + spiky.points[b]) * 0.5f),
                  bound + 1e-6);
        EXPECT_LE(length(held.points[ca] - (spiky.points[c] + spiky.points[a]) * 0.5f),
                  bound + 1e-6);
    }
    // a bound nothing reaches: the plain step, bit for bit
    EXPECT_EQ(post::loopSubdivide(spiky, 10.0).points, free.points);
}

} // namespace
} // namespace fluidsurf
