// Device::Auto's rule (Context.h, autoGpuParticles; backend::AutoDevice): a run with fewer
// particles than the GPU needs to pay (a frame's times the frames in the run, at the run's
// threads) takes the CPU, says why, and leaves the context on Auto afterwards; larger runs and
// other devices are left alone. On any machine, GPU or not.
#include "backend/Backend.h"

#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Scenes.h>

#include <gtest/gtest.h>

#include <cmath>
#include <stdexcept>

using namespace fluidsurf;

TEST(AutoDevice, TheThresholdGrowsWithTheThreadsAsMeasured)
{
    EXPECT_DOUBLE_EQ(autoGpuParticles(4), 1e6); // (the H200 host's crossing at 4 threads)
    EXPECT_NEAR(autoGpuParticles(8), 2.73e6, 0.01e6);
    EXPECT_NEAR(autoGpuParticles(16), 7.46e6, 0.01e6);
    EXPECT_DOUBLE_EQ(autoGpuParticles(0), autoGpuParticles(1)); // (no thread count below one)
    for (int t = 1; t < 256; ++t)
        EXPECT_LT(autoGpuParticles(t), autoGpuParticles(t + 1)) << t;
}

TEST(AutoDevice, ASmallRunTakesTheCpuAndTheContextStaysOnAuto)
{
    Context ctx(Device::Auto);
    ctx.setThreads(1); // (one thread on any machine: the threshold is autoGpuParticles(1))
    const double pays = autoGpuParticles(1);
    const size_t below = size_t(pays) - 1, at = size_t(std::ceil(pays));
    {
        const backend::AutoDevice d(ctx, below);
        EXPECT_EQ(ctx.device(), Device::Cpu);
        EXPECT_NE(d.why().find("auto:"), std::string::npos) << d.why();
        EXPECT_NE(d.why().find("at 1 thread"), std::string::npos) << d.why();
    }
    EXPECT_EQ(ctx.device(), Device::Auto);
    {
        const backend::AutoDevice d(ctx, at);
        EXPECT_EQ(ctx.device(), Device::Auto);
        EXPECT_EQ(d.why(), "");
    }
    // Frames share the context: ten frames of a tenth of the threshold and a bit pay.
    ctx.setFramesInRun(10);
    {
        const backend::AutoDevice d(ctx, at / 10 + 1);
        EXPECT_EQ(ctx.device(), Device::Auto);
    }
    {
        const backend::AutoDevice d(ctx, below / 10);
        EXPECT_EQ(ctx.device(), Device::Cpu);
        EXPECT_NE(d.why().find("10 frames"), std::string::npos) << d.why();
    }
    ctx.setFramesInRun(0); // (taken as one)
    EXPECT_EQ(ctx.framesInRun(), 1u);
    // Back to Auto when the frame's work throws.
    try {
        const backend::AutoDevice d(ctx, 10);
        throw std::runtime_error("a stage failed");
    } catch (const std::runtime_error&) {
    }
    EXPECT_EQ(ctx.device(), Device::Auto);
}

TEST(AutoDevice, OtherDevicesAreLeftAlone)
{
    for (const Device device : {Device::Cpu, Device::Cuda}) {
        Context ctx(device);
        const backend::AutoDevice d(ctx, 10);
        EXPECT_EQ(ctx.device(), device);
        EXPECT_EQ(d.why(), "");
    }
}

TEST(AutoDevice, ASmallFrameOnAutoIsTheCpusGridAndSaysWhy)
{
    SceneParams sp;
    sp.count = 3000;
    const ParticleSet ps = generateScene(Scene::Drop, sp);
    const Params p = Params::fromRadius(sp.radius);
    Context automatic(Device::Auto), cpu(Device::Cpu);
    const RasterizeResult a = rasterizeParticles(ps, p, automatic);
    const RasterizeResult c = rasterizeParticles(ps, p, cpu);
    EXPECT_EQ(a.stats.device.rfind("cpu (auto: ", 0), 0u) << a.stats.device;
    EXPECT_EQ(c.stats.device, "cpu");
    EXPECT_EQ(automatic.device(), Device::Auto);
    ASSERT_TRUE(a.grid && c.grid);
    EXPECT_TRUE(a.grid->tree().hasSameTopology(c.grid->tree()));
    size_t differ = 0;
    auto acc = c.grid->getConstAccessor();
    for (auto v = a.grid->tree().cbeginValueOn(); v; ++v)
        differ += *v != acc.getValue(v.getCoord());
    EXPECT_EQ(differ, 0u);
}
