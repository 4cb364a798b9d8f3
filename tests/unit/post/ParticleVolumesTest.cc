// ParticleVolumesTest.cc - VolumeTarget::Particles (issue 64): which closed component holds each
// particle, against boxes whose insides are known (one of them inside out, one nested in a
// hollow); and reconstructions whose closed components come out enclosing their own particles'
// volume, sum (2r)^3, closed and manifold, where the raw surface's target leaves them short.
#include "post/ParticleVolumes.h"
#include "util/Lanes.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/PostProcess.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/Scenes.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <tuple>

namespace fluidsurf {
namespace {

/// An axis-aligned box [lo, hi], twelve triangles, outward (or inward when flipped).
void addBox(TriangleMesh& m, Vec3f lo, Vec3f hi, bool flipped = false)
{
    const uint32_t b = uint32_t(m.points.size());
    for (int k = 0; k < 8; ++k)
        m.points.push_back(Vec3f(k & 1 ? hi.x : lo.x, k & 2 ? hi.y : lo.y, k & 4 ? hi.z : lo.z));
    // each face's corners counter-clockwise seen from outside
    const uint32_t faces[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                  {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (const auto& f : faces) {
        std::array<uint32_t, 3> t1{b + f[0], b + f[1], b + f[2]}, t2{b + f[0], b + f[2], b + f[3]};
        if (flipped) std::swap(t1[1], t1[2]), std::swap(t2[1], t2[2]);
        m.triangles.push_back(t1), m.triangles.push_back(t2);
    }
}

/// The register widths this CPU runs: 2 doubles, and 4 where it has AVX2.
std::vector<int> registerLanes()
{
    return util::doubleRegisterLanes() == 4 ? std::vector<int>{2, 4} : std::vector<int>{2};
}

} // namespace

TEST(ParticleVolumes, EachParticleIsInTheComponentThatHoldsIt)
{
    TriangleMesh m;
    addBox(m, Vec3f(0, 0, 0), Vec3f(1, 1, 1));                         // a
    addBox(m, Vec3f(3, 0.2f, 0.1f), Vec3f(4, 0.9f, 0.7f));             // b
    addBox(m, Vec3f(0, 3, 0), Vec3f(3, 6, 3));                         // c, with a hollow
    addBox(m, Vec3f(1, 4, 1), Vec3f(2, 5, 2), true);                   // the hollow (faces inward)
    addBox(m, Vec3f(1.25f, 4.25f, 1.25f), Vec3f(1.75f, 4.75f, 1.75f)); // d, in the hollow
    const post::Components c = post::findComponents(m);
    ASSERT_EQ(c.volume.size(), 5u);
    ASSERT_GT(c.volume[0], 0);
    ASSERT_LT(c.volume[c.ofPoint[24]], 0) << "the hollow's faces point into it";
    const std::vector<Vec3f> points = {
        {0.5f, 0.5f, 0.5f},   // in a
        {0.9f, 0.13f, 0.77f}, // in a, off-centre
        {-0.5f, 0.5f, 0.5f},  // before a along the ray: outside
        {2.f, 0.5f, 0.5f},    // between a and b: outside
        {3.5f, 0.5f, 0.5f},   // in b
        {5.f, 0.5f, 0.5f},    // beyond everything
        {0.5f, 3.5f, 0.5f},   // in c, below the hollow
        {0.5f, 4.5f, 1.5f},   // in c, the ray crossing the hollow and d after it
        {1.5f, 4.5f, 1.1f},   // in the hollow, not in d: outside
        {1.5f, 4.5f, 1.5f},   // in d
        {0.5f, 0.5f, 9.f},    // above all, outside the grid of columns
        {1.f, 0.5f, 0.5f},    // on a's face x = 1 (a's or no one's, as floats fall)
        {0.5f, 0.f, 0.5f},    // on a's face y = 0, the ray along it
        {2.5f, 4.5f, 1.5f},   // in c, beyond the hollow
    };
    ParticleVolumes pv;
    pv.positions = points.data(), pv.count = points.size(), pv.radius = 0.1;
    for (int lanes : registerLanes()) {
        SCOPED_TRACE(lanes);
        const std::vector<uint32_t> of =
            post::componentsOfParticles(m, c.ofPoint, c, pv, 0.3, lanes);
        const uint32_t a = c.ofPoint[0], b = c.ofPoint[8], cc = c.ofPoint[16], d = c.ofPoint[32];
        const uint32_t none = post::kNoComponent;
        const std::vector<uint32_t> want = {a, a, none, none, b, none, cc, cc, none, d, none};
        ASSERT_EQ(of.size(), want.size() + 3);
        for (size_t i = 0; i < want.size(); ++i)
            EXPECT_EQ(of[i], want[i]) << "point " << i;
        EXPECT_TRUE(of[11] == a || of[11] == none);
        EXPECT_TRUE(of[12] == a || of[12] == none);
        EXPECT_EQ(of[13], cc);
    }
}

TEST(ParticleVolumes, TwoAndFourDoublesARegisterGiveOneAnswer)
{
    // a raw reconstruction of a drop scene: a pool and droplets, most particles deep inside
    SceneParams sp;
    sp.count = 20000, sp.radius = 0.01;
    const ParticleSet ps = generateScene(Scene::Drop, sp);
    ReconstructParams p = ReconstructParams::fromRadius(sp.radius);
    p.post.decimate = 0, p.post.smooth = 0, p.post.subdivide = 0;
    Context ctx;
    const TriangleMesh m = reconstruct(ps, p, ctx).mesh;
    const post::Components c = post::findComponents(m);
    ParticleVolumes pv;
    pv.positions = ps.positions.data(), pv.count = ps.size(), pv.radius = sp.radius;
    const std::vector<uint32_t> two = post::componentsOfParticles(m, c.ofPoint, c, pv, 0.01, 2);
    EXPECT_GT(size_t(std::count_if(two.begin(), two.end(),
                                   [](uint32_t k) { return k != post::kNoComponent; })),
              ps.size() * 9 / 10);
    for (int lanes : registerLanes())
        EXPECT_EQ(post::componentsOfParticles(m, c.ofPoint, c, pv, 0.01, lanes), two) << lanes;
    EXPECT_THROW(post::componentsOfParticles(m, c.ofPoint, c, pv, 0.01, 3), ValueError);
}

namespace {

ReconstructParams withVolume(double r, VolumeTarget v)
{
    ReconstructParams p = ReconstructParams::fromRadius(r);
    p.post.volume = v;
    p.post.isolated = IsolatedMode::Drop;
    return p;
}

} // namespace

TEST(ParticleVolumes, ComponentsEncloseTheirParticlesVolumes)
{
    // two lattice blocks and a ball, their lowest x at 0, 2 and 4 (each less than 1 wide): each
    // its own component
    const double r = 0.025;
    ParticleSet ps;
    std::vector<int> partOf; // each particle's part
    int part = 0;
    for (auto [scene, count] : {std::tuple{Scene::Block, 4096}, std::tuple{Scene::Block, 1000},
                                std::tuple{Scene::Ball, 3000}}) {
        SceneParams sp;
        sp.radius = r, sp.count = size_t(count), sp.jitter = 0.2, sp.seed = 9;
        const ParticleSet one = generateScene(scene, sp);
        float lo = 1e30f;
        for (const Vec3f& q : one.positions)
            lo = std::min(lo, q.x);
        for (const Vec3f& q : one.positions) {
            ps.positions.push_back(Vec3f(q.x - lo + 2.f * float(part), q.y, q.z));
            partOf.push_back(part);
        }
        ++part;
    }
    Context ctx;
    const ReconstructResult mesh = reconstruct(ps, withVolume(r, VolumeTarget::Mesh), ctx);
    const ReconstructResult parts = reconstruct(ps, withVolume(r, VolumeTarget::Particles), ctx);
    const double particleVolume = double(ps.size()) * std::pow(2 * r, 3);
    const MeshReport mr = checkMesh(mesh.mesh), pr = checkMesh(parts.mesh);
    EXPECT_TRUE(pr.watertight()) << describe(pr);
    EXPECT_EQ(pr.components, 3u);
    EXPECT_EQ(parts.mesh.triangles.size(), mesh.mesh.triangles.size()) << "only points move";
    EXPECT_LT(mr.volume, 0.98 * particleVolume) << "the raw surface's target leaves them short";
    EXPECT_NEAR(pr.volume / particleVolume, 1.0, 0.01);
    // OpenMesh's decimation cannot trace points back, so the components are found again after
    // it: the particles' targets must be taken again there
    ReconstructParams openMesh = withVolume(r, VolumeTarget::Particles);
    openMesh.post.decimator = Decimator::OpenMesh;
    EXPECT_NEAR(checkMesh(reconstruct(ps, openMesh, ctx).mesh).volume / particleVolume, 1.0, 0.01);
    // each component its own particles' volume
    const post::Components c = post::findComponents(parts.mesh);
    ASSERT_EQ(c.volume.size(), 3u);
    double want[3] = {0, 0, 0}, got[3] = {0, 0, 0};
    for (size_t i = 0; i < ps.size(); ++i)
        want[partOf[i]] += std::pow(2 * r, 3);
    for (size_t v = 0; v < parts.mesh.points.size(); ++v) {
        const int k = int(std::floor((parts.mesh.points[v].x + 0.5f) / 2));
        ASSERT_TRUE(k >= 0 && k < 3);
        got[k] = c.volume[c.ofPoint[v]];
    }
    for (int k = 0; k < 3; ++k)
        EXPECT_NEAR(got[k] / want[k], 1.0, 0.015) << "part " << k;
}

TEST(ParticleVolumes, AMeshAloneKeepsItsOwnVolumes)
{
    // post-processing a mesh file has no particles: the default target falls back to the mesh's
    SceneParams sp;
    sp.radius = 0.025, sp.count = 3000, sp.jitter = 0.3;
    const ParticleSet ps = generateScene(Scene::Ball, sp);
    ReconstructParams raw = ReconstructParams::fromRadius(sp.radius);
    raw.post.decimate = 0, raw.post.smooth = 0, raw.post.subdivide = 0;
    Context ctx;
    const TriangleMesh m = reconstruct(ps, raw, ctx).mesh;
    PostProcessParams particles, mesh;
    ASSERT_EQ(particles.volume, VolumeTarget::Particles) << "the default";
    mesh.volume = VolumeTarget::Mesh;
    const TriangleMesh a = postProcessMesh(m, particles, ctx), b = postProcessMesh(m, mesh, ctx);
    EXPECT_EQ(a.points, b.points);
    EXPECT_NEAR(checkMesh(a).volume / checkMesh(m).volume, 1.0, 0.002);
    EXPECT_EQ(volumeTargetFromName("particles"), VolumeTarget::Particles);
    EXPECT_STREQ(volumeTargetName(VolumeTarget::Mesh), "mesh");
    EXPECT_THROW(volumeTargetFromName("cubes"), ValueError);
}

} // namespace fluidsurf
