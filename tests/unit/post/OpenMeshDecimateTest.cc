// OpenMeshDecimateTest.cc - OpenMesh's decimater on our arrays (post/OpenMeshDecimate), the
// baseline of our own decimation: it reaches the target, keeps a sphere round and a surface
// closed, and refuses what OpenMesh cannot hold.
#include "post/OpenMeshDecimate.h"
#include "post/IsolatedSpheres.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/MeshLevelSet.h>
#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Scenes.h>

#include <gtest/gtest.h>

#include <cmath>

namespace fluidsurf {
namespace {

TEST(OpenMeshDecimate, SphereKeepsItsShapeAtAQuarterOfTheTriangles)
{
    Context ctx;
    const TriangleMesh fine = post::unitIcosphere(4); // 5,120 triangles
    const TriangleMesh coarse = post::decimateOpenMesh(fine, 1280, ctx);
    EXPECT_LE(coarse.triangles.size(), 1280u);
    EXPECT_GE(coarse.triangles.size(), 1200u);
    const MeshReport r = checkMesh(coarse);
    EXPECT_TRUE(r.watertight()) << describe(r);
    EXPECT_EQ(r.unusedVertices, 0u);
    // collapses keep vertices near the surface they came from: within 1% of the radius
    for (const Vec3f& p : coarse.points)
        EXPECT_NEAR(std::sqrt(double(p.x) * p.x + double(p.y) * p.y + double(p.z) * p.z), 1.0,
                    0.01);
    EXPECT_NEAR(r.volume, checkMesh(fine).volume, 0.02 * checkMesh(fine).volume);
}

TEST(OpenMeshDecimate, SurfaceStaysClosedAtAFifthOfTheTriangles)
{
    Context ctx;
    SceneParams sp;
    sp.count = 20000;
    const ParticleSet ps = generateScene(Scene::Drop, sp);
    const TriangleMesh raw =
        meshLevelSet(*rasterizeParticles(ps, Params::fromRadius(sp.radius)).grid);
    const size_t target = raw.triangles.size() / 5; // the thesis' 80% removed
    const TriangleMesh d = post::decimateOpenMesh(raw, target, ctx);
    EXPECT_LE(d.triangles.size(), target);
    const MeshReport before = checkMesh(raw), after = checkMesh(d);
    EXPECT_TRUE(after.watertight()) << describe(after);
    EXPECT_EQ(after.components, before.components);
    EXPECT_NEAR(after.volume, before.volume, 0.01 * before.volume);
}

TEST(OpenMeshDecimate, NonManifoldInputIsAValueError)
{
    Context ctx;
    // three triangles on one edge
    TriangleMesh m;
    m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, -1, 0}, {0, 0, 1}};
    m.triangles = {{0, 1, 2}, {1, 0, 3}, {0, 1, 4}};
    EXPECT_THROW(post::decimateOpenMesh(m, 1, ctx), ValueError);
}

// A cancel (Ctrl-C through the context) stops OpenMesh's serial decimater, which went on for its
// minutes whatever the signals (issue 63).
TEST(OpenMeshDecimate, ACancelStopsIt)
{
    const TriangleMesh fine = post::unitIcosphere(5); // 20,480 triangles
    Context ctx;
    size_t calls = 0;
    ctx.setProgress([&](const ProgressEvent&) { return ++calls < 3; });
    EXPECT_THROW(post::decimateOpenMesh(fine, 100, ctx), Cancelled);
    EXPECT_EQ(calls, 3u);
}

} // namespace
} // namespace fluidsurf
