// Spacing estimate: exact on lattices, and equal to a brute-force nearest-neighbour median.
#include <fluidsurf/Scenes.h>
#include <fluidsurf/SpacingEstimate.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <random>

using namespace fluidsurf;

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
    for (size_t i = 0; i < ps.size(); ++i) {
        double best = INFINITY;
        for (size_t j = 0; j < ps.size(); ++j) {
            if (i == j) continue;
            const Vec3f d = ps.positions[j] - ps.positions[i];
            best = std::min(best,
                            std::sqrt(double(d.x) * d.x + double(d.y) * d.y + double(d.z) * d.z));
        }
        nn.push_back(best);
    }
    std::nth_element(nn.begin(), nn.begin() + nn.size() / 2, nn.end());
    const SpacingEstimate e = estimateSpacing(ps);
    EXPECT_NEAR(e.medianNearest, nn[nn.size() / 2], 1e-6);
    EXPECT_EQ(e.sampled, ps.size());
}
