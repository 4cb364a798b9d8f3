// Whether the CLI starts making the CUDA context while it reads (tools/cli/Frames.h,
// worthPreparingDevice): for --device auto only where a frame of the run could reach the GPU's
// threshold, the largest file at a particle per 6 bytes times the frames; compressed or unreadable
// inputs are prepared for. Files here are sparse: their sizes cost no disk.
#include "cli/Frames.h"

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <string>
#include <vector>

using namespace fluidsurf;
using namespace fluidsurf::cli;

namespace {

std::string sizedFile(const std::string& name, off_t bytes)
{
    const std::string path = ::testing::TempDir() + "fluidsurf_prepare_" + name;
    std::FILE* f = std::fopen(path.c_str(), "wb");
    EXPECT_TRUE(f != nullptr);
    if (f) std::fclose(f);
    EXPECT_EQ(::truncate(path.c_str(), bytes), 0);
    return path;
}

std::vector<FrameJob> jobsOf(const std::vector<std::string>& inputs)
{
    std::vector<FrameJob> jobs;
    for (const std::string& i : inputs)
        jobs.push_back({i, i + ".ply", int(jobs.size())});
    return jobs;
}

std::vector<size_t> all(const std::vector<FrameJob>& jobs)
{
    std::vector<size_t> v;
    for (size_t i = 0; i < jobs.size(); ++i)
        v.push_back(i);
    return v;
}

} // namespace

TEST(PrepareDevice, AutoPreparesOnlyWhereAFrameCouldReachTheGpu)
{
    Context ctx(Device::Auto);
    ctx.setThreads(1); // the threshold: autoGpuParticles(1) on any machine
    const double pays = autoGpuParticles(1);
    // Just under the threshold at 6 bytes a particle, and just over it.
    const std::string under = sizedFile("under.xyz", off_t(6 * pays) - 60);
    const std::string over = sizedFile("over.xyz", off_t(6 * pays) + 60);
    const auto one = jobsOf({under}), big = jobsOf({over});
    EXPECT_FALSE(worthPreparingDevice(ctx, one, all(one)));
    EXPECT_TRUE(worthPreparingDevice(ctx, big, all(big)));
    // Frames share the context: two of the small one reach it; none to do prepares nothing.
    const auto two = jobsOf({under, under});
    EXPECT_TRUE(worthPreparingDevice(ctx, two, all(two)));
    EXPECT_FALSE(worthPreparingDevice(ctx, two, {}));
    EXPECT_FALSE(worthPreparingDevice(ctx, two, {1}));
    // Compressed or unreadable: any number of particles.
    for (const char* name : {"small.bgeo.gz", "small.VTU", "small.vtp", "small.vdb"}) {
        const auto j = jobsOf({sizedFile(name, 100)});
        EXPECT_TRUE(worthPreparingDevice(ctx, j, all(j))) << name;
    }
    const auto missing = jobsOf({::testing::TempDir() + "fluidsurf_prepare_missing.xyz"});
    EXPECT_TRUE(worthPreparingDevice(ctx, missing, all(missing)));
}

TEST(PrepareDevice, CudaAlwaysAndCpuNever)
{
    const auto tiny = jobsOf({sizedFile("tiny.xyz", 10)});
    EXPECT_TRUE(worthPreparingDevice(Context(Device::Cuda), tiny, all(tiny)));
    const auto big = jobsOf({sizedFile("huge.xyz", off_t(1) << 36)});
    EXPECT_FALSE(worthPreparingDevice(Context(Device::Cpu), big, all(big)));
}
