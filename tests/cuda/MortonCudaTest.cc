// CUDA Morton codes against a bit-by-bit interleaving on the host. Skipped without a GPU.
#include "facade/Device.h"
#include <fluidsurf/Error.h>

#include <gtest/gtest.h>

#include <cmath>
#include <random>

using namespace fluidsurf;

namespace {
uint64_t referenceCode(const Vec3f& p, const Vec3f& o, float cell)
{
    const float inv = 1.f / cell; // the kernel's documented arithmetic: floor((p - o) * (1/cell))
    uint64_t c[3];
    for (int a = 0; a < 3; ++a) {
        const float f = std::floor((p[a] - o[a]) * inv);
        c[a] = uint64_t(std::min(std::max(f, 0.f), float((1 << 21) - 1)));
    }
    uint64_t code = 0;
    for (int bit = 0; bit < 21; ++bit)
        for (int a = 0; a < 3; ++a)
            code |= ((c[a] >> bit) & 1ull) << (3 * bit + a);
    return code;
}
} // namespace

TEST(MortonCuda, MatchesHostInterleaving)
{
    const cuda::DeviceInfo dev = cuda::queryDevice();
    if (!dev.usable) GTEST_SKIP() << dev.reason;
    std::mt19937 rng(1);
    std::uniform_real_distribution<float> u(-0.5f, 40.f);
    std::vector<Vec3f> pts(200003);
    for (Vec3f& p : pts)
        p = Vec3f(u(rng), u(rng), u(rng));
    pts[0] = Vec3f(-10.f, 1e9f, 0.f); // clamped on both ends
    const Vec3f origin(0.f, 0.f, 0.f);
    const std::vector<uint64_t> codes = cuda::mortonCodes(pts.data(), pts.size(), origin, 0.05f);
    ASSERT_EQ(codes.size(), pts.size());
    for (size_t i = 0; i < pts.size(); ++i)
        ASSERT_EQ(codes[i], referenceCode(pts[i], origin, 0.05f)) << "particle " << i;
}

TEST(MortonCuda, DeviceQueryNeverThrows)
{
    const cuda::DeviceInfo dev = cuda::queryDevice();
    if (dev.usable) {
        EXPECT_FALSE(dev.name.empty());
        EXPECT_GT(dev.memoryBytes, 0u);
    } else {
        EXPECT_FALSE(dev.reason.empty());
        EXPECT_THROW(cuda::mortonCodes(nullptr, 1, Vec3f(), 1.f), Error);
    }
}
