// AdaptiveGridTest.cc - the 3-level grid (thesis ch. 6): the sub-sampling rule against its
// definition, the level fields against an analytic field (each point evaluated once, copies and
// sub-samples exact), the mesher closed on analytic spheres under level maps with as many
// transitions as possible, and the whole path on generated scenes and the real frames: closed,
// close to the uniform mesh of the finest voxel, the same through a .vdb and for any thread count.
#include "TestData.h"
#include "adaptive/LevelFields.h"
#include "adaptive/LevelMap.h"
#include "adaptive/Levels.h"

#include <fluidsurf/AdaptiveGrid.h>
#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/MeshLevelSet.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/Scenes.h>
#include <fluidsurf/io/LevelSetIO.h>
#include <fluidsurf/io/ParticleIO.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>
#include <set>
#include <tuple>

namespace fluidsurf {
namespace {

using adaptive::kLevel2;
using adaptive::kLevel3;
using openvdb::Coord;

/// Level maps over the coarse cells [lo, hi]^3: a checkerboard (every face a transition), or
/// random levels, level 2 with probability level2Share.
adaptive::LevelTree::Ptr levelMap(int lo, int hi, unsigned seed, double level2Share = 0.5)
{
    auto t = std::make_shared<adaptive::LevelTree>(0);
    std::mt19937 rng(seed);
    std::bernoulli_distribution two(level2Share);
    for (int z = lo; z <= hi; ++z)
        for (int y = lo; y <= hi; ++y)
            for (int x = lo; x <= hi; ++x) {
                const int level = seed == 0 ? ((x + y + z) & 1 ? kLevel3 : kLevel2)
                                            : (two(rng) ? kLevel2 : kLevel3);
                t->setValueOn(Coord(x, y, z), level);
            }
    return t;
}

TEST(AdaptiveLevels, SubsampledPointsAreThoseOnTheClosedBoxOfALevel2Cell)
{
    const auto levels = levelMap(-2, 1, 7);
    adaptive::LevelLookup lookup(*levels);
    size_t yes = 0, no = 0;
    for (int z = -9; z <= 9; ++z)
        for (int y = -9; y <= 9; ++y)
            for (int x = -9; x <= 9; ++x) {
                const Coord p(x, y, z);
                bool expected = false;
                if ((x | y | z) & 1)
                    for (auto v = levels->cbeginValueOn(); v; ++v) {
                        const Coord c = v.getCoord();
                        bool in = *v == kLevel2;
                        for (int a = 0; a < 3; ++a)
                            in = in && 4 * c[a] <= p[a] && p[a] <= 4 * c[a] + 4;
                        expected = expected || in;
                    }
                ASSERT_EQ(lookup.subsampled(p), expected) << p;
                (expected ? yes : no) += 1;
            }
    EXPECT_GT(yes, 100u);
    EXPECT_GT(no, 100u);
}

TEST(AdaptiveLevels, Level2IslandsJoinLevel3AndLevel2RegionsStay)
{
    // One layer of coarse cells (z = 0), 12 x 12, level 3 but for: a lone level-2 cell, a 2 x 2
    // block, a strip one cell wide along x, and the rows y >= 9 (a region with straight borders).
    adaptive::LevelTree levels(0);
    auto expectedLevel = [](int x, int y) {
        if (y >= 9) return kLevel2;                               // region: stays
        if (x >= 2 && x <= 3 && y >= 2 && y <= 3) return kLevel2; // block: 2 against 2
        return kLevel3; // the lone cell (8, 2) and the strip y = 6 join level 3
    };
    for (int y = 0; y < 12; ++y)
        for (int x = 0; x < 12; ++x) {
            const bool two =
                y >= 9 || (x >= 2 && x <= 3 && y >= 2 && y <= 3) || (x == 8 && y == 2) || y == 6;
            levels.setValueOn(Coord(x, y, 0), two ? kLevel2 : kLevel3);
        }
    const adaptive::LevelTree before(levels);
    Context ctx;
    const size_t moved = adaptive::closeLevel2Islands(levels, ctx);
    EXPECT_EQ(moved, 13u); // the lone cell and the strip's 12
    EXPECT_EQ(levels.activeVoxelCount(), before.activeVoxelCount()); // nothing meshed or unmeshed
    for (int y = 0; y < 12; ++y)
        for (int x = 0; x < 12; ++x)
            ASSERT_EQ(levels.getValue(Coord(x, y, 0)), expectedLevel(x, y)) << x << ", " << y;

    // On random maps: level 3 stays level 3, and what is left is a fixed point (no level-2 cell
    // with more level-3 than level-2 face neighbours), checked cell by cell.
    for (unsigned seed = 1; seed <= 3; ++seed) {
        const auto map = levelMap(-3, 3, seed, 0.75);
        const adaptive::LevelTree start(*map);
        adaptive::closeLevel2Islands(*map, ctx);
        size_t level2 = 0;
        for (auto v = start.cbeginValueOn(); v; ++v) {
            const int now = map->getValue(v.getCoord());
            if (*v == kLevel3) ASSERT_EQ(now, kLevel3) << v.getCoord();
            if (now != kLevel2) continue;
            ++level2;
            int at2 = 0, at3 = 0;
            for (int f = 0; f < 6; ++f) {
                Coord q = v.getCoord();
                q[f / 2] += f & 1 ? 1 : -1;
                const int l = map->isValueOn(q) ? map->getValue(q) : 0;
                at2 += l == kLevel2, at3 += l == kLevel3;
            }
            ASSERT_LE(at3, at2) << v.getCoord();
        }
        EXPECT_GT(level2, 0u) << seed; // the rule does not simply take everything
    }
}

/// The level fields on exactly the map a test gives (no probes, no islands closed): the
/// sub-sampling and the mesher are tested under maps with as many transitions as possible.
const adaptive::Refinement kMapAsGiven{0.f, false};

/// phi of a sphere, exact at world points, clamped to the background like the field.
struct Sphere
{
    openvdb::Vec3d centre;
    double radius;
    float value(const openvdb::Vec3d& w, float background) const
    {
        const double d = (w - centre).length() - radius;
        return float(std::clamp(d, -double(background), double(background)));
    }
};

/// An evaluator at voxel size dx that records every point it evaluates.
field::FieldEvaluator analytic(const Sphere& s, double dx, std::multiset<Coord>& seen)
{
    return [&s, dx, &seen](openvdb::FloatTree& t) {
        for (auto v = t.beginValueOn(); v; ++v) {
            seen.insert(v.getCoord());
            v.setValue(s.value(v.getCoord().asVec3d() * dx, t.background()));
        }
    };
}

TEST(AdaptiveLevels, EveryPointIsEvaluatedOnceAndTheRestIsCopiedOrSubsampledExactly)
{
    const double dx = 0.1;
    const Sphere sphere{{0.03, -0.02, 0.01}, 0.61};
    auto levels = levelMap(-2, 1, 3);
    openvdb::FloatTree level2(float(6 * dx));
    std::multiset<Coord> seen2, seen3;
    Context ctx;
    adaptive::LevelFieldStats stats;
    const openvdb::FloatTree::Ptr level3 =
        adaptive::fillLevels(level2, *levels, analytic(sphere, 2 * dx, seen2),
                             analytic(sphere, dx, seen3), float(3 * dx), kMapAsGiven, ctx, &stats);
    for (const auto* seen : {&seen2, &seen3})
        for (auto it = seen->begin(); it != seen->end(); it = seen->upper_bound(*it))
            ASSERT_EQ(seen->count(*it), 1u) << "evaluated twice: " << *it;
    EXPECT_EQ(stats.level3Evaluated, seen3.size());
    adaptive::LevelLookup lookup(*levels);
    auto v2 = [&](const Coord& p) {
        float v;
        EXPECT_TRUE(level2.probeValue(Coord(p.x() >> 1, p.y() >> 1, p.z() >> 1), v)) << p;
        return v;
    };
    size_t copied = 0, subsampled = 0, evaluated = 0;
    for (auto v = level3->cbeginValueOn(); v; ++v) {
        const Coord p = v.getCoord();
        int odd[3], n = 0;
        for (int a = 0; a < 3; ++a)
            if (p[a] & 1) odd[n++] = a;
        if (n == 0) {
            ASSERT_EQ(*v, std::clamp(v2(p), float(-3 * dx), float(3 * dx)));
            ++copied;
        } else if (lookup.subsampled(p)) {
            // linear along the odd axis, or the mean of the face's four corners
            Coord a = p, b = p;
            a[odd[0]] -= 1, b[odd[0]] += 1;
            double expected = 0.5 * (v2(a) + v2(b));
            if (n == 2) {
                Coord c = a, d = b, e = a, f = b;
                c[odd[1]] -= 1, d[odd[1]] -= 1, e[odd[1]] += 1, f[odd[1]] += 1;
                expected = 0.25 * (double(v2(c)) + v2(d) + v2(e) + v2(f));
            }
            ASSERT_EQ(n < 3, true);
            ASSERT_NEAR(*v, expected, 1e-6) << p;
            ++subsampled;
        } else {
            ASSERT_EQ(*v, sphere.value(p.asVec3d() * dx, float(3 * dx))) << p;
            ASSERT_EQ(seen3.count(p), 1u);
            ++evaluated;
        }
    }
    EXPECT_EQ(subsampled, stats.subsampled);
    EXPECT_GT(copied, 0u);
    EXPECT_GT(subsampled, 0u);
    EXPECT_GT(evaluated, 0u);
    // Every level-3 cell holds all of its 125 points.
    for (auto v = levels->cbeginValueOn(); v; ++v)
        if (*v == kLevel3)
            for (int i = 0; i < 125; ++i)
                ASSERT_TRUE(level3->isValueOn(Coord(4 * v.getCoord().x() + i % 5,
                                                    4 * v.getCoord().y() + i / 5 % 5,
                                                    4 * v.getCoord().z() + i / 25)));
}

/// The analytic sphere's adaptive grid under a level map, filled by fillLevels.
AdaptiveGrid sphereGrid(const Sphere& sphere, double dx, adaptive::LevelTree::Ptr levels)
{
    auto level2 = std::make_shared<openvdb::FloatTree>(float(6 * dx));
    std::multiset<Coord> seen2, seen3;
    Context ctx;
    auto level3 =
        adaptive::fillLevels(*level2, *levels, analytic(sphere, 2 * dx, seen2),
                             analytic(sphere, dx, seen3), float(3 * dx), kMapAsGiven, ctx);
    AdaptiveGrid g;
    g.level2 = openvdb::FloatGrid::create(level2);
    g.level2->setTransform(openvdb::math::Transform::createLinearTransform(2 * dx));
    g.level3 = openvdb::FloatGrid::create(level3);
    g.level3->setTransform(openvdb::math::Transform::createLinearTransform(dx));
    g.levels = openvdb::Int32Grid::create(levels);
    g.levels->setTransform(openvdb::math::Transform::createLinearTransform(4 * dx));
    return g;
}

/// The uniform marching-cubes mesh of the sphere at voxel h over the same box.
TriangleMesh uniformSphere(const Sphere& sphere, double h, double extent)
{
    auto grid = openvdb::FloatGrid::create(float(3 * h));
    grid->setTransform(openvdb::math::Transform::createLinearTransform(h));
    const int n = int(std::ceil(extent / h));
    for (int z = -n; z <= n; ++z)
        for (int y = -n; y <= n; ++y)
            for (int x = -n; x <= n; ++x)
                grid->tree().setValueOn(Coord(x, y, z),
                                        sphere.value(openvdb::Vec3d(x, y, z) * h, float(3 * h)));
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    return meshLevelSet(*grid);
}

/// Largest distance of the points from the sphere.
double offSphere(const TriangleMesh& mesh, const Sphere& sphere)
{
    double worst = 0;
    for (const Vec3f& p : mesh.points)
        worst = std::max(worst, std::abs((openvdb::Vec3d(p.x, p.y, p.z) - sphere.centre).length() -
                                         sphere.radius));
    return worst;
}

TEST(AdaptiveMesh, SpheresUnderEveryKindOfLevelMapAreClosedAndBetweenTheUniformMeshes)
{
    const double dx = 0.1;
    for (unsigned seed : {0u, 1u, 2u, 3u, 4u})
        for (const Sphere& sphere :
             {Sphere{{0.0, 0.0, 0.0}, 0.8}, Sphere{{0.13, -0.07, 0.21}, 0.93},
              Sphere{{0.4, 0.4, 0.4}, 0.57}}) {
            const AdaptiveGrid grid = sphereGrid(sphere, dx, levelMap(-3, 2, seed));
            const TriangleMesh fine = uniformSphere(sphere, dx, 1.3),
                               coarse = uniformSphere(sphere, 2 * dx, 1.3);
            size_t cutTriangles = 0;
            for (bool merge : {false, true}) { // the cracks cut, then merged where they can be
                Context ctx;
                AdaptiveMeshStats stats;
                const TriangleMesh mesh = meshAdaptiveGrid(grid, ctx, &stats, {merge});
                const MeshReport report = checkMesh(mesh);
                SCOPED_TRACE("seed " + std::to_string(seed) + ", radius " +
                             std::to_string(sphere.radius) + (merge ? ", merged" : ", cut"));
                EXPECT_TRUE(report.watertight()) << describe(report);
                EXPECT_EQ(report.components, 1u);
                EXPECT_EQ(report.unusedVertices, 0u);
                EXPECT_EQ(stats.openCracks, 0u);
                EXPECT_GT(stats.level2Triangles, 0u);
                EXPECT_GT(stats.level3Triangles, 0u);
                EXPECT_EQ(stats.level2Triangles + stats.level3Triangles + stats.patchTriangles,
                          mesh.triangles.size());
                if (!merge) {
                    EXPECT_EQ(stats.mergedCrackPoints, 0u);
                    EXPECT_GT(stats.patchTriangles, 0u); // the maps cut it at many transitions
                    cutTriangles = mesh.triangles.size();
                } else {
                    // Each merged point takes a level-3 triangle away instead of adding one.
                    EXPECT_GT(stats.mergedCrackPoints, 0u);
                    EXPECT_LT(mesh.triangles.size(), cutTriangles);
                }
                // Off the sphere by about the uniform mesh's at 2 dx: points on a transition
                // face sit on the bilinear interpolant of a 2 dx face, up to about twice the
                // chord error of a 2 dx edge. Its volume between the uniform meshes' at 2 dx
                // and dx (marching cubes' chords cut into the sphere).
                EXPECT_LE(offSphere(mesh, sphere), 2.5 * offSphere(coarse, sphere));
                const double vFine = checkMesh(fine).volume, vCoarse = checkMesh(coarse).volume;
                ASSERT_LT(vCoarse, vFine);
                EXPECT_GT(report.volume, vCoarse);
                EXPECT_LT(report.volume, vFine);
                ASSERT_EQ(mesh.normals.size(), mesh.points.size());
            }
        }
}

ReconstructParams rawParams(double r, bool adaptive)
{
    ReconstructParams p = ReconstructParams::fromRadius(r);
    p.field.adaptive = adaptive;
    p.post.isolated = IsolatedMode::Drop;
    p.post.decimate = 0, p.post.smooth = 0, p.post.subdivide = 0;
    return p;
}

/// The points of mesh inside level-3 regions, as a mesh of points: every coarse cell within one
/// level-3 voxel of the point is at level 3, so no value its cell was cut from is sub-sampled
/// from level 2.
TriangleMesh level3Points(const TriangleMesh& mesh, const AdaptiveGrid& grid)
{
    const double cell = grid.levels->voxelSize()[0];
    openvdb::Int32Grid::ConstAccessor acc = grid.levels->getConstAccessor();
    TriangleMesh out;
    for (const Vec3f& p : mesh.points) {
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            const double q = double(p[a]) / cell;
            lo[a] = int(std::floor(q - 0.25)), hi[a] = int(std::floor(q + 0.25)); // dx: cell / 4
        }
        bool all = true;
        for (int z = lo[2]; z <= hi[2] && all; ++z)
            for (int y = lo[1]; y <= hi[1] && all; ++y)
                for (int x = lo[0]; x <= hi[0] && all; ++x) {
                    int level = 0;
                    all = acc.probeValue(openvdb::Coord(x, y, z), level) && level == kLevel3;
                }
        if (!all) continue;
        out.triangles.push_back({uint32_t(out.points.size()), uint32_t(out.points.size()),
                                 uint32_t(out.points.size())});
        out.points.push_back(p);
    }
    return out;
}

/// How many of points have no point of `to` within `tolerance` on every axis.
size_t unmatched(const std::vector<Vec3f>& points, std::vector<Vec3f> to, double tolerance)
{
    auto byX = [](const Vec3f& p, const Vec3f& q) { return p.x < q.x; };
    std::sort(to.begin(), to.end(), byX);
    const float t = float(tolerance);
    size_t n = 0;
    for (const Vec3f& p : points) {
        bool found = false;
        for (auto q = std::lower_bound(to.begin(), to.end(), Vec3f{p.x - t, 0, 0}, byX);
             q != to.end() && q->x <= p.x + t && !found; ++q)
            found = std::abs(q->y - p.y) <= t && std::abs(q->z - p.z) <= t;
        n += !found;
    }
    return n;
}

/// The acceptance on one frame: closed like the uniform mesh, within 0.5 r of it both ways and
/// within 0.1 r inside level-3 regions, and no more triangles.
void expectCloseToUniform(const ParticleSet& ps, double r, const std::string& name)
{
    SCOPED_TRACE(name);
    Context ctx;
    const ReconstructResult uniform = reconstruct(ps, rawParams(r, false), ctx, name);
    const ReconstructResult adaptive = reconstruct(ps, rawParams(r, true), ctx, name);
    const MeshReport u = checkMesh(uniform.mesh), a = checkMesh(adaptive.mesh);
    EXPECT_EQ(a.watertight(), u.watertight()) << describe(a) << " / uniform: " << describe(u);
    EXPECT_EQ(a.boundaryEdges, 0u);
    EXPECT_EQ(a.nonManifoldEdges, 0u);
    EXPECT_EQ(a.misorientedEdges, 0u);
    EXPECT_EQ(adaptive.adaptiveMesh.openCracks, 0u);
    const double d = std::max(meshDistance(adaptive.mesh, uniform.mesh, 4 * r),
                              meshDistance(uniform.mesh, adaptive.mesh, 4 * r));
    EXPECT_LE(d, 0.5 * r) << "Hausdorff " << d / r << " r";
    // Inside level-3 regions the detail is the uniform mesh's (the issue: within 0.1 r; the same
    // values give the same points there). The strip one voxel wide along level-2 faces is cut
    // from sub-sampled values, and may be up to ~0.2 r off.
    const TriangleMesh fine = level3Points(adaptive.mesh, adaptive.adaptiveGrid);
    EXPECT_LE(meshDistance(fine, uniform.mesh, 4 * r), 0.1 * r)
        << fine.points.size() << " of " << adaptive.mesh.points.size() << " points inside level 3";
    EXPECT_LE(adaptive.mesh.triangles.size(), uniform.mesh.triangles.size());
}

TEST(AdaptiveReconstruct, GeneratedScenesAreClosedAndWithinHalfARadiusOfTheUniformMesh)
{
    for (Scene scene : {Scene::Drop, Scene::Ball, Scene::Slab, Scene::Block}) {
        SceneParams sp;
        sp.count = 20000;
        expectCloseToUniform(generateScene(scene, sp), sp.radius, sceneName(scene));
    }
}

TEST(AdaptiveReconstruct, WithEveryCellAtTheFinestLevelItIsTheUniformMesh)
{
    // Curvature threshold 0: every meshed cell is level 3, so the cells must cover every
    // surface cell of the uniform band, and the vertices must be the uniform mesher's (in
    // another order; within 1e-5 r: the gather sums a point's particles in an order that
    // depends on the leaf it is evaluated in, which differs between the two grids).
    SceneParams sp;
    sp.count = 20000;
    for (Scene scene : {Scene::Drop, Scene::Slab}) {
        const ParticleSet ps = generateScene(scene, sp);
        ReconstructParams all = rawParams(sp.radius, true);
        all.field.curvatureThreshold = 0;
        Context ctx;
        const ReconstructResult a = reconstruct(ps, all, ctx, "a");
        const ReconstructResult u = reconstruct(ps, rawParams(sp.radius, false), ctx, "u");
        EXPECT_EQ(a.field.level2Cells, 0u);
        EXPECT_EQ(a.adaptiveMesh.patchTriangles, 0u);
        EXPECT_EQ(a.mesh.triangles.size(), u.mesh.triangles.size());
        ASSERT_EQ(a.mesh.points.size(), u.mesh.points.size());
        EXPECT_EQ(unmatched(a.mesh.points, u.mesh.points, 1e-5 * sp.radius), 0u)
            << sceneName(scene);
    }
}

TEST(AdaptiveReconstruct, Level2VerticesAwayFromLevel3AreTheUniformMeshsVertices)
{
    // A level-2 edge's crossing away from level 3 is placed with the level-3 probe at its
    // middle, on the level-3 half-edge: where the uniform mesh of dx has its vertex (within
    // 1e-5 r, as above). Level 2's own linear guess along 2 dx would be off by up to ~0.2 r.
    SceneParams sp;
    sp.count = 20000;
    for (Scene scene : {Scene::Drop, Scene::Slab}) {
        SCOPED_TRACE(sceneName(scene));
        const ParticleSet ps = generateScene(scene, sp);
        Context ctx;
        const ReconstructResult a = reconstruct(ps, rawParams(sp.radius, true), ctx, "a");
        const ReconstructResult u = reconstruct(ps, rawParams(sp.radius, false), ctx, "u");
        // The points with no level-3 cell among the 27 coarse cells around them.
        const AdaptiveGrid& g = a.adaptiveGrid;
        const double cell = g.levels->voxelSize()[0];
        openvdb::Int32Grid::ConstAccessor acc = g.levels->getConstAccessor();
        std::vector<Vec3f> flat;
        for (const Vec3f& p : a.mesh.points) {
            const Coord c(int(std::floor(p.x / cell)), int(std::floor(p.y / cell)),
                          int(std::floor(p.z / cell)));
            bool near3 = false;
            for (int i = 0; i < 27 && !near3; ++i)
                near3 = acc.getValue(c.offsetBy(i % 3 - 1, i / 3 % 3 - 1, i / 9 - 1)) == kLevel3;
            if (!near3) flat.push_back(p);
        }
        EXPECT_GT(flat.size(), a.mesh.points.size() / 10) << "too few level-2 points to judge";
        EXPECT_GT(a.field.level2CrossingProbes, flat.size() / 2);
        EXPECT_EQ(unmatched(flat, u.mesh.points, 1e-5 * sp.radius), 0u)
            << "of " << flat.size() << " level-2 points";
    }
}

TEST(AdaptiveReconstruct, RealFramesAreClosedAndWithinHalfARadiusOfTheUniformMesh)
{
    FLUIDSURF_REQUIRE_SHARED_DATA();
    for (const test::RealFrame& f : test::kRealFrames) {
        if (!f.fluid) continue;
        const ParticleSet ps = io::readParticles(test::sharedData() + "/real/" + f.name);
        expectCloseToUniform(ps, f.radius, f.name);
    }
}

TEST(AdaptiveReconstruct, TheVdbMeshesToTheSameMeshForAnyThreadCount)
{
    SceneParams sp;
    sp.count = 20000;
    const ParticleSet ps = generateScene(Scene::Drop, sp);
    Context all, one;
    one.setThreads(1);
    const ReconstructResult a = reconstruct(ps, rawParams(sp.radius, true), all, "drop");
    const ReconstructResult b = reconstruct(ps, rawParams(sp.radius, true), one, "drop");
    EXPECT_EQ(a.mesh.points, b.mesh.points);
    EXPECT_EQ(a.mesh.triangles, b.mesh.triangles);
    ASSERT_FALSE(a.adaptiveGrid.empty());
    EXPECT_EQ(a.levelSet, a.adaptiveGrid.level2);
    test::TempDir dir;
    io::writeLevelSet(a.adaptiveGrid.grids(), dir.path("a.vdb"));
    const io::LevelSetFile file = io::readLevelSetFile(dir.path("a.vdb"));
    ASSERT_FALSE(file.adaptive.empty());
    EXPECT_EQ(file.adaptive.level2->getGridClass(), openvdb::GRID_LEVEL_SET);
    EXPECT_EQ(file.adaptive.level3->getGridClass(), openvdb::GRID_LEVEL_SET);
    Context ctx;
    const TriangleMesh again = meshAdaptiveGrid(file.adaptive, ctx);
    EXPECT_EQ(again.points, a.mesh.points);
    EXPECT_EQ(again.triangles, a.mesh.triangles);
    // By name, one grid is an ordinary level set.
    EXPECT_TRUE(io::readLevelSetFile(dir.path("a.vdb"), "surface_fine").adaptive.empty());
}

TEST(AdaptiveGridFile, ALevelsGridWithoutFittingLevelsIsOneClearError)
{
    auto levels = openvdb::Int32Grid::create(0);
    levels->setName(AdaptiveGrid::kLevelsName);
    levels->setTransform(openvdb::math::Transform::createLinearTransform(0.04));
    auto level2 = openvdb::FloatGrid::create(0.06f), level3 = openvdb::FloatGrid::create(0.03f);
    level2->setName(AdaptiveGrid::kLevel2Name), level3->setName(AdaptiveGrid::kLevel3Name);
    level2->setTransform(openvdb::math::Transform::createLinearTransform(0.02));
    level3->setTransform(openvdb::math::Transform::createLinearTransform(0.01));
    auto message = [](const openvdb::GridPtrVec& grids) {
        try {
            AdaptiveGrid::fromGrids(grids, "f.vdb");
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_TRUE(AdaptiveGrid::fromGrids({level2}, "f.vdb").empty()); // an ordinary level set
    EXPECT_FALSE(AdaptiveGrid::fromGrids({levels, level2, level3}, "f.vdb").empty());
    EXPECT_NE(message({levels, level2}).find("without float grids 'surface' and 'surface_fine'"),
              std::string::npos)
        << message({levels, level2});
    level3->setTransform(openvdb::math::Transform::createLinearTransform(0.015));
    EXPECT_NE(message({levels, level2, level3}).find("voxel sizes are not 4:2:1"),
              std::string::npos)
        << message({levels, level2, level3});
    // through the reader: the same message, naming the file
    level3->setTransform(openvdb::math::Transform::createLinearTransform(0.01));
    test::TempDir dir;
    io::writeLevelSet({levels, level2}, dir.path("broken.vdb"));
    try {
        io::readLevelSetFile(dir.path("broken.vdb"));
        ADD_FAILURE() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find(dir.path("broken.vdb")), std::string::npos);
    }
}

TEST(AdaptiveReconstruct, RefusesTheBaselineMethodsAndABadThreshold)
{
    Params p = Params::fromRadius(0.025);
    p.adaptive = true;
    p.method = FieldMethod::GatherFull;
    EXPECT_THROW(p.validate(), ValueError);
    p.method = FieldMethod::NarrowBand;
    p.curvatureThreshold = -1;
    EXPECT_THROW(p.validate(), ValueError);
    p.curvatureThreshold = 1;
    EXPECT_NO_THROW(p.validate());
}

} // namespace
} // namespace fluidsurf
