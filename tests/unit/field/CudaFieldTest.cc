// CudaFieldTest.cc - the field on the GPU (Params::device = Cuda) against the CPU path: the
// narrow band computed on the device from the sort on (the same classes, isolated particles and
// active topology as the CPU; values within 1e-5 r, the same zero crossings), and the gather
// alone for gather-full. Skipped with the reason where there is no usable GPU (CI); there, a
// CUDA request must fail with a clear error.
#include "TestData.h"

#include "unit/field/RequireGpu.h"

#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Scenes.h>

#include <gtest/gtest.h>

#include <cmath>

namespace fluidsurf {
namespace {

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
    size_t signFlips = 0, n = 0;
    for (auto it = cpu.grid->cbeginValueOn(); it; ++it, ++n) {
        const float a = *it, b = acc.getValue(it.getCoord());
        worst = std::max(worst, double(std::abs(a - b)));
        if (std::abs(a) > 1e-5 * p.radius && (a < 0) != (b < 0)) ++signFlips;
    }
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
        Params full = Params::fromRadius(sp.radius);
        full.method = FieldMethod::GatherFull;
        expectSameField(ps, full, std::string(sceneName(scene)) + "_gather_full");
    }
    // Per-particle radii (pscale) and isolated particles kept as spheres.
    ParticleSet ps = generateScene(Scene::Drop, sp);
    Attribute pscale;
    pscale.name = "pscale";
    pscale.floats.resize(ps.size());
    for (size_t i = 0; i < ps.size(); ++i)
        pscale.floats[i] = float(sp.radius * (0.8 + 0.4 * double(i % 7) / 6));
    ps.attributes.push_back(pscale);
    Params p = Params::fromRadius(sp.radius);
    p.keepIsolated = true;
    expectSameField(ps, p, "drop_pscale_keep_isolated");
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
    // Auto falls back to the CPU: the same grid as an explicit CPU run.
    const RasterizeResult autoRun = rasterizeParticles(ps, p, automatic);
    EXPECT_EQ(autoRun.stats.device, "cpu");
    const RasterizeResult cpuRun = rasterizeParticles(ps, p, cpu);
    EXPECT_TRUE(autoRun.grid->tree().hasSameTopology(cpuRun.grid->tree()));
    EXPECT_THROW(deviceFromName("gpu"), ValueError);
}

} // namespace
} // namespace fluidsurf
