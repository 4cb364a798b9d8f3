// Spacing estimate: exact on lattices, and equal to a brute-force nearest-neighbour median.
#include <fluidsurf/Scenes.h>
#include <fluidsurf/SpacingEstimate.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace fluidsurf;

namespace {
/// The distance from particle q to its nearest other particle, by brute force in double.
double bruteForceNearest(const ParticleSet& ps, size_t q)
{
    double best = INFINITY;
    for (size_t j = 0; j < ps.size(); ++j) {
        if (j == q) continue;
        const Vec3f d = ps.positions[j] - ps.positions[q];
        best = std::min(best, std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z));
    }
    return best;
}
} // namespace

TEST(SpacingEstimate, LatticeSpacingIsTwiceTheRadius)
{
    SceneParams p;
    p.radius = 0.025;
    p.count = 8000;
    const SpacingEstimate e = estimateSpacing(generateScene(Scene::Block, p));
    EXPECT_NEAR(e.medianNearest, 0.05, 1e-6);
    EXPECT_NEAR(e.radius, 0.025, 1e-6);
    // a single flat layer (zero-thickness bounding box) too
    p.layers = 1;
    p.jitter = 0;
    EXPECT_NEAR(estimateSpacing(generateScene(Scene::Slab, p)).radius, 0.025, 1e-6);
}

TEST(SpacingEstimate, MatchesBruteForceOnRandomPoints)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    ParticleSet ps;
    for (int i = 0; i < 3000; ++i)
        ps.positions.emplace_back(u(rng), u(rng) * 0.3f, u(rng) * 5.f);
    std::vector<double> nn;
    for (size_t i = 0; i < ps.size(); ++i)
        nn.push_back(bruteForceNearest(ps, i));
    std::nth_element(nn.begin(), nn.begin() + nn.size() / 2, nn.end());
    const SpacingEstimate e = estimateSpacing(ps);
    EXPECT_NEAR(e.medianNearest, nn[nn.size() / 2], 1e-6);
    EXPECT_EQ(e.sampled, ps.size());
}

TEST(SpacingEstimate, EverySampledParticleIsMeasuredOnce)
{
    // 30,011 particles, 1,000 of them sampled: particle q = floor(s n / samples) for sample s
    // (every 30th or 31st). Ten of the sampled ones lie far out, alone: they count as isolated,
    // and the median is that of the other sampled particles' nearest distances, by brute force.
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> u(0.f, 1.f);
    ParticleSet ps;
    const size_t n = 30011, samples = 1000;
    for (size_t i = 0; i < n; ++i)
        ps.positions.emplace_back(u(rng) * 2.f, u(rng), u(rng) * 0.5f);
    auto sampled = [&](size_t s) { return s * n / samples; };
    for (size_t s = 1; s <= 10; ++s) // 1,000 apart
        ps.positions[sampled(7 * s)] = Vec3f(1000.f * float(s), 0.5f, 0.25f);
    std::vector<double> nn;
    for (size_t s = 0; s < samples; ++s) {
        const size_t q = sampled(s);
        if (s % 7 == 0 && s >= 7 && s <= 70) continue; // the lone ones
        nn.push_back(bruteForceNearest(ps, q));
    }
    std::nth_element(nn.begin(), nn.begin() + nn.size() / 2, nn.end());
    const SpacingEstimate e = estimateSpacing(ps, samples);
    EXPECT_EQ(e.sampled, samples);
    EXPECT_EQ(e.isolated, 10u);
    EXPECT_EQ(e.medianNearest, nn[nn.size() / 2]);
}
