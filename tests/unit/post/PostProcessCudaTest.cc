// PostProcessCudaTest.cc - post-processing's steps on the GPU against the CPU's (backend/):
// - the smoothing (smoothMesh): the same points, to the bit, on the decimated meshes of generated
//   scenes and real frames (the default chain's input to it), with and without the flattening,
//   on an open bumpy patch (its border stays), on a mesh with unused points and a non-manifold
//   edge, and with Taubin's rounds only;
// - which component holds each particle (componentsOfParticles): the same answer on the
//   smoothed meshes of those scenes and frames, on nested spheres (a cavity, a droplet in it), and
//   where a ray crosses more components than a device thread keeps;
// - the whole default chain on the GPU gives the CPU's file.
// Skipped where there is no usable GPU.
#include "../field/RequireGpu.h"
#include "GridMesh.h"
#include "TestData.h"
#include "post/Decimate.h"
#include "post/IsolatedSpheres.h"
#include "post/ParticleVolumes.h"
#include "post/Smooth.h"

#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/Scenes.h>
#include <fluidsurf/io/ParticleIO.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace fluidsurf {
namespace {

/// The GPU's smoothing of mesh is the CPU's, point for point and bit for bit.
void expectSameSmoothing(const TriangleMesh& mesh, const post::SmoothParams& params,
                         const std::string& what)
{
    SCOPED_TRACE(what);
    Context ctx;
    TriangleMesh a = mesh, b = mesh;
    backend::makeCpuBackend()->smoothMesh(a, params, ctx);
    backend::makeCudaBackend()->smoothMesh(b, params, ctx);
    ASSERT_EQ(a.points.size(), b.points.size());
    EXPECT_TRUE(a.triangles == b.triangles);
    EXPECT_EQ(a.normals.size(), b.normals.size());
    size_t differ = 0, first = a.points.size();
    for (size_t v = 0; v < a.points.size(); ++v)
        if (std::memcmp(&a.points[v], &b.points[v], sizeof(Vec3f)) != 0)
            first = std::min(first, v), ++differ;
    EXPECT_EQ(differ, 0u) << "first at point " << first;
    // and the smoothing did something (else the test proves nothing; a frame whose particles
    // are all isolated has no mesh to smooth)
    size_t moved = 0;
    for (size_t v = 0; v < mesh.points.size(); ++v)
        moved += !(a.points[v] == mesh.points[v]);
    if (mesh.points.size() >= 100) EXPECT_GT(moved, mesh.points.size() / 10);
}

/// The default chain's smoothing parameters at voxel `voxel` (PostProcess.cc's bounds).
post::SmoothParams defaults(double voxel, bool flatten = true)
{
    post::SmoothParams sp;
    sp.rounds = 6, sp.maxMove = 0.2 * voxel;
    sp.flatten = flatten, sp.flatMove = 0.4 * voxel, sp.voxel = voxel;
    return sp;
}

/// The raw marching-cubes mesh of ps at radius r, decimated as the default chain does.
TriangleMesh decimatedMesh(const ParticleSet& ps, double r)
{
    ReconstructParams p = ReconstructParams::fromRadius(r);
    p.post.decimate = 0, p.post.smooth = 0, p.post.subdivide = 0;
    p.post.isolated = IsolatedMode::Drop;
    Context ctx;
    TriangleMesh raw = reconstruct(ps, p, ctx).mesh;
    post::DecimateTarget to{size_t(std::ceil(double(raw.triangles.size()) * 0.2))};
    to.maxStep = 0.15 * r;
    return post::decimate(std::move(raw), to);
}

TEST(SmoothCuda, SameBitsOnGeneratedScenes)
{
    FLUIDSURF_REQUIRE_GPU();
    for (Scene scene : {Scene::Drop, Scene::Slab, Scene::Ball, Scene::Sheet}) {
        SceneParams sp;
        sp.count = 60000;
        const TriangleMesh mesh = decimatedMesh(generateScene(scene, sp), sp.radius);
        expectSameSmoothing(mesh, defaults(sp.radius), sceneName(scene));
        expectSameSmoothing(mesh, defaults(sp.radius, false),
                            std::string(sceneName(scene)) + " without flattening");
    }
}

TEST(SmoothCuda, SameBitsOnRealFrames)
{
    FLUIDSURF_REQUIRE_GPU();
    FLUIDSURF_REQUIRE_SHARED_DATA();
    for (const test::RealFrame& f : test::kRealFrames) {
        const ParticleSet ps = io::readParticles(test::sharedData() + "/real/" + f.name);
        expectSameSmoothing(decimatedMesh(ps, f.radius), defaults(f.radius), f.name);
    }
}

TEST(SmoothCuda, SameBitsOnAnOpenPatchUnusedPointsAndANonManifoldEdge)
{
    FLUIDSURF_REQUIRE_GPU();
    // a bumpy open patch: wide bumps (flattened) and a fixed hash of small ones
    TriangleMesh m = test::gridMesh(60, [](uint32_t i, uint32_t j) {
        return 0.3 * std::sin(0.2 * i) * std::cos(0.15 * j) +
               0.05 * double((i * 2654435761u + j * 40503u) % 1000) / 999.0;
    });
    expectSameSmoothing(m, defaults(1.0), "open patch");
    // a point no triangle uses, and a third triangle on one edge
    m.points.push_back(Vec3f(100.f, 100.f, 100.f));
    m.points.push_back(Vec3f(30.5f, 30.5f, 5.f));
    m.triangles.push_back(
        {uint32_t(31 * 61 + 30), uint32_t(31 * 61 + 31), uint32_t(m.points.size() - 1)});
    expectSameSmoothing(m, defaults(1.0), "unused point, non-manifold edge");
    post::SmoothParams taubin = defaults(1.0, false);
    taubin.rounds = 20;
    expectSameSmoothing(m, taubin, "Taubin's rounds only");
}

/// The GPU's answer to which component holds each particle is the CPU's.
void expectSameComponents(const TriangleMesh& mesh, const std::vector<Vec3f>& particles,
                          double cell, const std::string& what, size_t minimumHeld = 1)
{
    SCOPED_TRACE(what);
    const post::Components c = post::findComponents(mesh);
    ParticleVolumes pv;
    pv.positions = particles.data(), pv.count = particles.size(), pv.radius = cell;
    Context ctx;
    const std::vector<uint32_t> a =
        backend::makeCpuBackend()->componentsOfParticles(mesh, c.ofPoint, c, pv, cell, ctx);
    const std::vector<uint32_t> b =
        backend::makeCudaBackend()->componentsOfParticles(mesh, c.ofPoint, c, pv, cell, ctx);
    ASSERT_EQ(a.size(), b.size());
    size_t differ = 0, held = 0;
    for (size_t i = 0; i < a.size(); ++i)
        differ += a[i] != b[i], held += a[i] != post::kNoComponent;
    EXPECT_EQ(differ, 0u);
    EXPECT_GE(held, minimumHeld); // (an answer of "none" everywhere would prove nothing)
}

TEST(ParticlesInsideCuda, SameAnswerOnSmoothedScenesAndRealFrames)
{
    FLUIDSURF_REQUIRE_GPU();
    for (Scene scene : {Scene::Drop, Scene::Slab, Scene::Ball, Scene::Sheet, Scene::Jet}) {
        SceneParams sp;
        sp.count = 60000;
        const ParticleSet ps = generateScene(scene, sp);
        const TriangleMesh mesh =
            post::smoothAlongNormals(decimatedMesh(ps, sp.radius), defaults(sp.radius));
        expectSameComponents(mesh, ps.positions, sp.radius, sceneName(scene), ps.size() / 2);
    }
    if (test::sharedData().empty()) return;
    for (const test::RealFrame& f : test::kRealFrames) {
        const ParticleSet ps = io::readParticles(test::sharedData() + "/real/" + f.name);
        const TriangleMesh mesh =
            post::smoothAlongNormals(decimatedMesh(ps, f.radius), defaults(f.radius));
        expectSameComponents(mesh, ps.positions, f.radius, f.name, 0);
    }
}

TEST(ParticlesInsideCuda, SameAnswerInNestedSpheresAndThroughManyComponents)
{
    FLUIDSURF_REQUIRE_GPU();
    // a ball of radius 3 with a cavity of radius 2 (inside out) holding a droplet of radius 1,
    // and points on a lattice through all of them and outside
    TriangleMesh mesh;
    auto add = [&](double radius, Vec3f centre, bool insideOut) {
        TriangleMesh s = post::unitIcosphere(4);
        const uint32_t base = uint32_t(mesh.points.size());
        for (const Vec3f& p : s.points)
            mesh.points.push_back(centre + p * float(radius));
        for (auto t : s.triangles) {
            if (insideOut) std::swap(t[1], t[2]);
            mesh.triangles.push_back({base + t[0], base + t[1], base + t[2]});
        }
    };
    const Vec3f origin(0.f, 0.f, 0.f);
    add(3, origin, false), add(2, origin, true), add(1, origin, false);
    std::vector<Vec3f> lattice;
    for (int i = -8; i <= 8; ++i)
        for (int j = -8; j <= 8; ++j)
            for (int k = -8; k <= 8; ++k)
                lattice.push_back(Vec3f(0.41f * i + 0.013f, 0.39f * j, 0.43f * k));
    expectSameComponents(mesh, lattice, 0.2, "nested spheres", 100);
    // 80 small balls in a row along each axis: rays through all of them
    for (int a = 0; a < 3; ++a)
        for (int n = 0; n < 80; ++n) {
            Vec3f at(20.f, 20.f, 20.f);
            at[a] += 1.0f * float(n);
            add(0.4, at, false);
        }
    for (int a = 0; a < 3; ++a) // (the rays run along whichever axis the surface faces most)
        for (int n = 0; n < 400; ++n) {
            Vec3f at(20.03f, 20.05f, 20.02f);
            at[a] = 20.f + 0.2f * float(n);
            lattice.push_back(at);
        }
    expectSameComponents(mesh, lattice, 0.2, "many components on one ray", 100);
}

TEST(SmoothCuda, TheDefaultChainOnTheGpuWritesTheCpusMesh)
{
    FLUIDSURF_REQUIRE_GPU();
    SceneParams sp;
    sp.count = 100000;
    const ParticleSet ps = generateScene(Scene::Drop, sp);
    const ReconstructParams p = ReconstructParams::fromRadius(sp.radius);
    Context cpu, gpu(Device::Cuda);
    const TriangleMesh a = reconstruct(ps, p, cpu, "cpu").mesh;
    const TriangleMesh b = reconstruct(ps, p, gpu, "gpu").mesh;
    ASSERT_EQ(a.points.size(), b.points.size());
    EXPECT_EQ(0, std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(Vec3f)));
    EXPECT_EQ(0, std::memcmp(a.normals.data(), b.normals.data(), a.normals.size() * sizeof(Vec3f)));
    EXPECT_TRUE(a.triangles == b.triangles);
    EXPECT_TRUE(checkMesh(b).watertight());
}

} // namespace
} // namespace fluidsurf
