// CudaFieldTest.cc - the field on the GPU (Params::device = Cuda) against the CPU path: the
// narrow band computed on the device from the sort on (the same classes, isolated particles and
// active topology as the CPU), and the gather alone for gather-full. The values are the CPU's to
// the bit where the CPU sums on 8 lanes (AVX2 and FMA, as on the GPU hosts), else within 1e-5 r
// with the same zero crossings; so the whole reconstruction, post-processing included, makes the
// same mesh on both. Skipped with the reason where there is no usable GPU (CI); there, a CUDA
// request must fail with a clear error.
#include "TestData.h"

#include "unit/field/RequireGpu.h"

#include "field/GatherField.h"

#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/Scenes.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>

namespace fluidsurf {
namespace {

/// ps with a radius attribute (pscale) of 0.8 r to 1.2 r.
ParticleSet withPscale(ParticleSet ps, double r)
{
    Attribute pscale;
    pscale.name = "pscale";
    pscale.floats.resize(ps.size());
    for (size_t i = 0; i < ps.size(); ++i)
        pscale.floats[i] = float(r * (0.8 + 0.4 * double(i % 7) / 6));
    ps.attributes.push_back(pscale);
    return ps;
}

/// CPU and CUDA grids of the same particles and parameters agree.
void expectSameField(const ParticleSet& ps, Params p, const std::string& what,
                     bool devicePipeline = true)
{
    Context onCpu(Device::Cpu), onGpu(Device::Cuda);
    const RasterizeResult cpu = rasterizeParticles(ps, p, onCpu, what);
    const RasterizeResult gpu = rasterizeParticles(ps, p, onGpu, what);
    EXPECT_NE(gpu.stats.device, "cpu") << what;
    // The narrow band must have run on the device from the sort on, not only its gather.
    bool deviceClassify = false;
    for (const StageTime& st : gpu.stats.gpuStages)
        deviceClassify |= st.name == "classify";
    EXPECT_EQ(deviceClassify,
              devicePipeline && p.method == FieldMethod::NarrowBand && ps.size() > 0)
        << what;
    EXPECT_EQ(gpu.stats.interior, cpu.stats.interior) << what;
    EXPECT_EQ(gpu.stats.surface, cpu.stats.surface) << what;
    EXPECT_EQ(gpu.stats.splash, cpu.stats.splash) << what;
    EXPECT_EQ(gpu.stats.isolated, cpu.stats.isolated) << what;
    EXPECT_EQ(gpu.isolatedParticles, cpu.isolatedParticles) << what;
    EXPECT_EQ(gpu.stats.bandCompletion, cpu.stats.bandCompletion) << what;
    EXPECT_EQ(gpu.stats.fieldEvaluations, cpu.stats.fieldEvaluations) << what;
    ASSERT_TRUE(cpu.grid->tree().hasSameTopology(gpu.grid->tree()))
        << what << ": active topology differs";
    auto acc = gpu.grid->getConstAccessor();
    double worst = 0;
    size_t signFlips = 0, n = 0, otherBits = 0;
    for (auto it = cpu.grid->cbeginValueOn(); it; ++it, ++n) {
        const float a = *it, b = acc.getValue(it.getCoord());
        worst = std::max(worst, double(std::abs(a - b)));
        if (std::abs(a) > 1e-5 * p.radius && (a < 0) != (b < 0)) ++signFlips;
        otherBits += std::memcmp(&a, &b, sizeof a) != 0;
    }
    if (field::fieldLanes() == 8) // the CPU's sums (GatherField.h); with 4 lanes they differ
        EXPECT_EQ(otherBits, 0u) << what << ": values with other bits, of " << n
                                 << " (largest difference " << worst / p.radius << " r)";
    EXPECT_LE(worst, 1e-5 * p.radius)
        << what << ": largest difference " << worst / p.radius << " r over " << n << " voxels";
    EXPECT_EQ(signFlips, 0u) << what << ": zero crossings differ";
    ::testing::Test::RecordProperty(what + "_worst_difference_in_r",
                                    std::to_string(worst / p.radius));
}

TEST(FieldCuda, MatchesCpuOnRealFrames)
{
    FLUIDSURF_REQUIRE_GPU();
    FLUIDSURF_REQUIRE_SHARED_DATA();
    for (const test::RealFrame& f : test::kRealFrames)
        expectSameField(io::readParticles(test::sharedData() + "/real/" + f.name),
                        Params::fromRadius(f.radius), f.name);
}

TEST(FieldCuda, MatchesCpuOnGeneratedScenesAndSettings)
{
    FLUIDSURF_REQUIRE_GPU();
    SceneParams sp;
    sp.count = 30000;
    for (Scene scene : {Scene::Block, Scene::Ball, Scene::Slab, Scene::Drop}) {
        const ParticleSet ps = generateScene(scene, sp);
        for (double voxel : {0.5, 1.0, 2.0})
            for (double support : {4.0, 8.0}) {
                Params p = Params::fromRadius(sp.radius);
                p.voxelSize = voxel * sp.radius, p.influenceRadius = support * sp.radius;
                expectSameField(ps, p,
                                std::string(sceneName(scene)) + "_voxel" + std::to_string(voxel) +
                                    "_R" + std::to_string(support));
            }
        Params zb = Params::fromRadius(sp.radius);
        zb.field = FieldKind::Zb05;
        expectSameField(ps, zb, std::string(sceneName(scene)) + "_zb05");
        Params scaled = Params::fromRadius(sp.radius);
        scaled.radiusScale = 1.096;
        expectSameField(ps, scaled, std::string(sceneName(scene)) + "_radius_scale");
        Params full = Params::fromRadius(sp.radius);
        full.method = FieldMethod::GatherFull;
        expectSameField(ps, full, std::string(sceneName(scene)) + "_gather_full");
    }
    // Per-particle radii (pscale) and isolated particles kept as spheres.
    const ParticleSet ps = withPscale(generateScene(Scene::Drop, sp), sp.radius);
    Params p = Params::fromRadius(sp.radius);
    p.keepIsolated = true;
    expectSameField(ps, p, "drop_pscale_keep_isolated");
    p.radiusScale = 1.096;
    expectSameField(ps, p, "drop_pscale_radius_scale");
}

TEST(FieldCuda, MatchesCpuOnSparseAndDegenerateFrames)
{
    FLUIDSURF_REQUIRE_GPU();
    const double r = 0.025;
    auto frame = [](std::vector<Vec3f> pts) {
        ParticleSet ps;
        ps.positions = std::move(pts);
        return ps;
    };
    for (bool keep : {false, true}) {
        Params p = Params::fromRadius(r);
        p.keepIsolated = keep;
        const std::string k = keep ? "_kept" : "_dropped";
        expectSameField(frame({Vec3f(0.1f, 0.2f, 0.3f)}), p, "one_particle" + k);
        // All isolated: with the particles dropped the band is empty.
        expectSameField(frame({Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0), Vec3f(-3, -2, 5)}),
                        p, "isolated" + k);
        // A pair (splash) plus a far isolated particle, at negative coordinates.
        expectSameField(frame({Vec3f(-5, -5, -5), Vec3f(-5.04f, -5, -5), Vec3f(7, 7, 7)}), p,
                        "pair" + k);
    }
    // A particle exactly on leaf and cell boundaries, and lattice rows at spacing 2r.
    std::vector<Vec3f> lattice;
    for (int i = 0; i < 20; ++i)
        for (int j = 0; j < 3; ++j)
            lattice.push_back(Vec3f(float(i * 2 * r), float(j * 2 * r), 0.2f));
    expectSameField(frame(lattice), Params::fromRadius(r), "lattice_rows");
}

/// The whole reconstruction (band, field, completion, marching cubes, post-processing, spheres)
/// on the GPU and on the CPU: the same mesh, byte for byte, where the CPU sums on 8 lanes.
void expectSameReconstruction(const ParticleSet& ps, ReconstructParams p, const std::string& what)
{
    SCOPED_TRACE(what);
    Context onCpu(Device::Cpu), onGpu(Device::Cuda);
    const ReconstructResult cpu = reconstruct(ps, p, onCpu, what);
    const ReconstructResult gpu = reconstruct(ps, p, onGpu, what);
    EXPECT_NE(gpu.field.device, "cpu");
    ASSERT_FALSE(cpu.mesh.empty());
    ASSERT_EQ(cpu.mesh.triangles.size(), gpu.mesh.triangles.size());
    ASSERT_EQ(cpu.mesh.points.size(), gpu.mesh.points.size());
    EXPECT_TRUE(cpu.mesh.triangles == gpu.mesh.triangles);
    EXPECT_EQ(0, std::memcmp(cpu.mesh.points.data(), gpu.mesh.points.data(),
                             cpu.mesh.points.size() * sizeof(Vec3f)));
    ASSERT_EQ(cpu.mesh.normals.size(), gpu.mesh.normals.size());
    EXPECT_EQ(0, std::memcmp(cpu.mesh.normals.data(), gpu.mesh.normals.data(),
                             cpu.mesh.normals.size() * sizeof(Vec3f)));
}

TEST(FieldCuda, TheWholeReconstructionMakesTheCpusMesh)
{
    FLUIDSURF_REQUIRE_GPU();
    if (field::fieldLanes() != 8) GTEST_SKIP() << "the CPU sums on 4 lanes here (no AVX2 and FMA)";
    FLUIDSURF_REQUIRE_SHARED_DATA();
    for (const test::RealFrame& f : test::kRealFrames)
        expectSameReconstruction(io::readParticles(test::sharedData() + "/real/" + f.name),
                                 ReconstructParams::fromRadius(f.radius), f.name);
    SceneParams sp;
    sp.count = 30000;
    const ParticleSet drop = generateScene(Scene::Drop, sp);
    ReconstructParams p = ReconstructParams::fromRadius(sp.radius);
    p.field.voxelSize = 0.5; // (in r) a finer grid: reach 8, columns of 2 slabs
    expectSameReconstruction(drop, p, "drop_voxel0.5");
    p = ReconstructParams::fromRadius(sp.radius);
    p.field.field = FieldKind::Zb05;
    expectSameReconstruction(drop, p, "drop_zb05");
}

TEST(FieldCuda, TheAnisotropicFieldsAreTheCpusToTheBit)
{
    // ssp07-aniso and yt10: classes, band and kernel shapes on the CPU, the gather on the device,
    // which tests kernels voxel by voxel where the CPU tests 2 x 2 x 2 blocks (AnisotropicSums.h:
    // the same bits either way, on 8 lanes or one voxel at a time).
    FLUIDSURF_REQUIRE_GPU();
    SceneParams sp;
    sp.count = 20000, sp.jitter = 0.3, sp.layers = 2;
    for (Scene scene : {Scene::Sheet, Scene::Jet, Scene::Slab, Scene::Drop}) {
        const ParticleSet ps = generateScene(scene, sp);
        const std::string name = std::string(sceneName(scene)) + "_aniso";
        Params p = Params::fromRadius(sp.radius);
        p.field = FieldKind::Ssp07Aniso;
        expectSameField(ps, p, name, false);
        Params stretched = p;
        stretched.anisotropyRatio = 2.5, stretched.centreSmoothing = 0.3;
        expectSameField(ps, stretched, name + "_stretched", false);
        Params fine = p;
        fine.voxelSize = 0.5 * sp.radius;
        expectSameField(ps, fine, name + "_voxel0.5", false);
        Params yt10 = stretched;
        yt10.field = FieldKind::Yt10;
        expectSameField(ps, yt10, std::string(sceneName(scene)) + "_yt10", false);
    }
    const ParticleSet ps = withPscale(generateScene(Scene::Drop, sp), sp.radius);
    Params p = Params::fromRadius(sp.radius);
    p.field = FieldKind::Ssp07Aniso, p.keepIsolated = true;
    expectSameField(ps, p, "drop_pscale_keep_isolated_aniso", false);
    p.field = FieldKind::Yt10;
    expectSameField(ps, p, "drop_pscale_keep_isolated_yt10", false);
    FLUIDSURF_REQUIRE_SHARED_DATA();
    for (const test::RealFrame& f : test::kRealFrames) {
        Params q = Params::fromRadius(f.radius);
        q.field = FieldKind::Ssp07Aniso;
        const ParticleSet frame = io::readParticles(test::sharedData() + "/real/" + f.name);
        expectSameField(frame, q, std::string(f.name) + "_aniso", false);
        q.field = FieldKind::Yt10;
        expectSameField(frame, q, std::string(f.name) + "_yt10", false);
        if (field::fieldLanes() != 8) continue; // (the post-processing's own sums)
        ReconstructParams rp = ReconstructParams::fromRadius(f.radius);
        rp.field.field = FieldKind::Ssp07Aniso, rp.post.smooth = 20;
        expectSameReconstruction(frame, rp, std::string(f.name) + "_aniso_smooth20");
    }
}

TEST(FieldCuda, ASupportOfManyVoxelsGoesToTheCpu)
{
    // R = 4r at voxel r / 30: 134 voxels of reach, 276 slabs a leaf axis; the device gather's bin
    // counters (276 x 16 x 16, 283 KB) pass any GPU's shared memory, so the CPU takes the band
    // and the field, says why, and the grid is the CPU's.
    FLUIDSURF_REQUIRE_GPU();
    ParticleSet ps;
    ps.positions = {Vec3f(0, 0, 0), Vec3f(1.5f, 0, 0), Vec3f(0.7f, 1.2f, 0.1f)};
    Params p = Params::fromRadius(1.0);
    p.voxelSize = 1.0 / 30;
    for (FieldMethod method : {FieldMethod::NarrowBand, FieldMethod::GatherFull}) {
        p.method = method;
        const std::string what = method == FieldMethod::NarrowBand ? "band" : "gather_full";
        expectSameField(ps, p, "support_of_134_voxels_" + what, false);
        Context onGpu(Device::Cuda);
        EXPECT_EQ(rasterizeParticles(ps, p, onGpu).stats.device,
                  "cpu (the support spans more voxels than the GPU's gather holds)")
            << what;
    }
}

TEST(FieldCuda, FarFromTheOriginTheCpuBandIsUsed)
{
    // Leaf keys on the device hold 2^20 leaves (8.4M voxels) either side of the origin. Beyond,
    // the CPU takes the frame and says so; the grid must not change. Spacing 2 at
    // x = 9e6 is still exact in float.
    FLUIDSURF_REQUIRE_GPU();
    ParticleSet ps;
    for (int i = 0; i < 12; ++i)
        for (int j = 0; j < 12; ++j)
            for (int k = 0; k < 12; ++k)
                ps.positions.push_back(Vec3f(9e6f + 2.f * i, 2.f * j, 2.f * k));
    expectSameField(ps, Params::fromRadius(1.0), "far_block", false);
    Context onGpu(Device::Cuda);
    EXPECT_EQ(rasterizeParticles(ps, Params::fromRadius(1.0), onGpu).stats.device.rfind("cpu (", 0),
              0u);
}

TEST(FieldCuda, RequestWithoutGpuFailsClearly)
{
    std::string why;
    if (backend::cudaUsable(&why)) GTEST_SKIP() << "a GPU is present: this checks the no-GPU path";
    SceneParams sp;
    sp.count = 1000;
    const ParticleSet ps = generateScene(Scene::Block, sp);
    const Params p = Params::fromRadius(sp.radius);
    Context cuda(Device::Cuda), automatic(Device::Auto), cpu(Device::Cpu);
    try {
        rasterizeParticles(ps, p, cuda);
        ADD_FAILURE() << "no error";
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("CUDA"), std::string::npos) << e.what();
    }
    // Auto falls back to the CPU: the same grid as an explicit CPU run. (A run of so many
    // frames that Auto's rule would take the GPU: AutoDeviceTest has the small runs.)
    automatic.setFramesInRun(100000000);
    const RasterizeResult autoRun = rasterizeParticles(ps, p, automatic);
    EXPECT_EQ(autoRun.stats.device, "cpu");
    const RasterizeResult cpuRun = rasterizeParticles(ps, p, cpu);
    EXPECT_TRUE(autoRun.grid->tree().hasSameTopology(cpuRun.grid->tree()));
    EXPECT_THROW(deviceFromName("gpu"), ValueError);
}

} // namespace
} // namespace fluidsurf
