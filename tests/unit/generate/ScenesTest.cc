// Generated scenes: determinism, lattice geometry, isolated droplets.
#include <fluidsurf/Error.h>
#include <fluidsurf/Scenes.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace fluidsurf;

namespace {
double dist(const Vec3f& a, const Vec3f& b)
{
    const double dx = double(a.x) - b.x, dy = double(a.y) - b.y, dz = double(a.z) - b.z;
    return std::sqrt(dx * dx + dy * dy + dz * dz);
}
} // namespace

TEST(Scenes, DeterministicForASeed)
{
    SceneParams p;
    p.count = 5000;
    p.seed = 3;
    const ParticleSet a = generateScene(Scene::Drop, p), b = generateScene(Scene::Drop, p);
    EXPECT_EQ(a.positions, b.positions);
    p.seed = 4;
    EXPECT_NE(a.positions, generateScene(Scene::Drop, p).positions);
}

TEST(Scenes, SingleBlockAndBall)
{
    SceneParams p;
    p.radius = 0.5;
    EXPECT_EQ(generateScene(Scene::Single, p).positions, std::vector<Vec3f>{Vec3f(0, 0, 0)});
    p.count = 1000;
    const ParticleSet block = generateScene(Scene::Block, p);
    ASSERT_EQ(block.size(), 1000u);
    EXPECT_EQ(block.positions.back(), Vec3f(9.f, 9.f, 9.f)) << "spacing is 2r";
    const ParticleSet ball = generateScene(Scene::Ball, p);
    const double rho = std::cbrt(3.0 * 1000 / (4 * M_PI)) * 2 * p.radius;
    size_t expected = 0; // brute-force lattice count
    const int m = int(std::ceil(rho));
    for (int i = -m; i <= m; ++i)
        for (int j = -m; j <= m; ++j)
            for (int k = -m; k <= m; ++k)
                expected += (i * i + j * j + k * k) * 1.0 <= rho * rho;
    EXPECT_EQ(ball.size(), expected);
    for (const Vec3f& q : ball.positions)
        ASSERT_LE(dist(q, Vec3f()), rho + 1e-6);
    EXPECT_EQ(ball.find(AttributeRole::Id)->ints.back(), int64_t(ball.size() - 1));
}

TEST(Scenes, SlabIsFlatWithBoundedJitter)
{
    SceneParams p;
    p.radius = 0.1;
    p.count = 4000;
    p.layers = 4;
    p.jitter = 0.1;
    const ParticleSet s = generateScene(Scene::Slab, p);
    const BBox3f box = s.bbox();
    EXPECT_FLOAT_EQ(box.min.z, 0.f);
    EXPECT_NEAR(box.max.z, 3 * 0.2, 1e-6);
    EXPECT_GE(box.min.x, -0.1f * 0.2f - 1e-6f);
}

TEST(Scenes, DropDropletsHaveNoNeighbourWithinTheSupport)
{
    SceneParams p;
    p.count = 20000;
    p.droplets = 5;
    const ParticleSet s = generateScene(Scene::Drop, p);
    const double h = 4 * p.radius;
    int isolated = 0;
    for (size_t i = 0; i < s.size(); ++i) {
        bool alone = true;
        for (size_t j = 0; j < s.size() && alone; ++j)
            alone = i == j || dist(s.positions[i], s.positions[j]) >= h;
        isolated += alone;
    }
    EXPECT_EQ(isolated, 5);
    // A deeper pool adds interior particles only: same bounding box in x and y.
    SceneParams deep = p;
    deep.poolDepthScale = 2;
    const ParticleSet d = generateScene(Scene::Drop, deep);
    EXPECT_GT(d.size(), s.size());
    EXPECT_EQ(d.bbox().min.x, s.bbox().min.x);
}

TEST(Scenes, InvalidParametersAreErrors)
{
    SceneParams p;
    p.radius = -1;
    EXPECT_THROW(generateScene(Scene::Ball, p), ValueError);
    EXPECT_THROW(sceneFromName("teapot"), ValueError);
}

TEST(Scenes, SheetIsAJitteredQuarterCylinderWall)
{
    SceneParams p;
    p.radius = 0.5, p.count = 4000, p.jitter = 0.2;
    for (int layers : {1, 2}) {
        p.layers = layers;
        const ParticleSet s = generateScene(Scene::Sheet, p);
        const int width = int(std::lround(std::sqrt(4000.0 / layers / 2)));
        ASSERT_EQ(s.size(), size_t(layers * width * 2 * width));
        // inner radius: the arc of 2 * width spacings is a quarter turn (at least 8 spacings)
        const double spacing = 2 * p.radius,
                     inner = std::max(8.0, 2 * width / (M_PI / 2)) * spacing;
        const double reach = std::sqrt(3.0) * p.jitter * spacing; // the jitter's longest offset
        for (size_t i = 0; i < s.size(); ++i) {
            const Vec3f q = s.positions[i];
            const double rho = std::hypot(double(q.x), double(q.z));
            const int layer = int(i / size_t(width * 2 * width));
            ASSERT_NEAR(rho, inner + layer * spacing, reach) << i;
            ASSERT_GE(q.y, -reach);
            ASSERT_LE(q.y, (width - 1) * spacing + reach);
            ASSERT_GE(std::atan2(double(q.z), double(q.x)), -reach / inner);
        }
    }
    p.layers = 65;
    EXPECT_THROW(generateScene(Scene::Sheet, p), ValueError);
}

TEST(Scenes, JetIsAThinArc)
{
    SceneParams p;
    p.radius = 0.5, p.count = 2000, p.jitter = 0.1, p.layers = 2;
    const ParticleSet s = generateScene(Scene::Jet, p);
    // slices of 4, one spacing apart along a parabola z = h (1 - (x / L)^2), h = L / 2
    ASSERT_EQ(s.size() % 4, 0u);
    // h from the particles at the top (x near 0: their offsets across cancel in the mean)
    double top = 0;
    size_t atTop = 0;
    for (const Vec3f& q : s.positions)
        if (std::fabs(q.x) < p.radius) top += q.z, ++atTop;
    ASSERT_GT(atTop, 0u);
    const double h = top / double(atTop), L = 2 * h;
    size_t far = 0;
    for (const Vec3f& q : s.positions) {
        // the distance from the arc, sampled finely
        double best = 1e9;
        for (int k = 0; k <= 20000; ++k) {
            const double x = -L + 2 * L * k / 20000.0, z = h * (1 - x * x / (L * L));
            best = std::min(best, std::hypot(double(q.x) - x, double(q.z) - z));
        }
        // the slice's corners lie half a spacing off in both directions across it (and jitter)
        far += std::hypot(best, double(q.y)) > std::sqrt(0.5) * 2 * p.radius + 0.2;
    }
    EXPECT_EQ(far, 0u);
    EXPECT_NEAR(s.size() / 4.0, 2000 / 4.0, 0.1 * 2000 / 4.0) << "slices one spacing apart";
}
