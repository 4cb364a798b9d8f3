// ParticleSet: roles by alias and shape, validation, non-finite filtering.
#include <fluidsurf/Error.h>
#include <fluidsurf/ParticleSet.h>

#include <gtest/gtest.h>

#include <cmath>

using namespace fluidsurf;

TEST(ParticleSet, RolesNeedTheRightShape)
{
    ParticleSet ps;
    ps.positions.resize(2);
    ps.addFloat("v", 1, {1, 2}); // a scalar named v is not a velocity
    ps.addFloat("Vel", 3, std::vector<float>(6, 1.f));
    ps.addInt("Idp", 1, {4, 5});
    ps.addFloat("pscale", 1, {0.1f, 0.2f});
    EXPECT_EQ(ps.find(AttributeRole::Velocity)->name, "Vel");
    EXPECT_EQ(ps.find(AttributeRole::Id)->name, "Idp");
    EXPECT_EQ(ps.find(AttributeRole::Radius)->name, "pscale");
    EXPECT_EQ(ps.find(AttributeRole::Density), nullptr);
}

TEST(ParticleSet, ValidateCatchesLengthMismatch)
{
    ParticleSet ps;
    ps.positions.resize(3);
    ps.addFloat("a", 2, std::vector<float>(5));
    EXPECT_THROW(ps.validate(), ValueError);
}

TEST(ParticleSet, DropNonFiniteKeepsAttributesAligned)
{
    ParticleSet ps;
    ps.positions = {{0, 0, 0}, {NAN, 0, 0}, {2, 2, 2}, {0, INFINITY, 0}, {4, 4, 4}};
    ps.addInt("id", 1, {0, 1, 2, 3, 4});
    ps.addFloat("v", 3, {0, 0, 0, 1, 1, 1, 2, 2, 2, 3, 3, 3, 4, 4, 4});
    EXPECT_EQ(ps.dropNonFinite(), 2u);
    EXPECT_EQ(ps.find("id")->ints, (std::vector<int64_t>{0, 2, 4}));
    EXPECT_EQ(ps.find("v")->floats, (std::vector<float>{0, 0, 0, 2, 2, 2, 4, 4, 4}));
    EXPECT_EQ(ps.positions[2], Vec3f(4, 4, 4));
}

TEST(ParticleSet, BoundsOnAllThreadsAreThePointsExtremes)
{
    // 300,001 points over several of boundsOf's chunks, each axis' extremes placed by hand in
    // different chunks; the bounds are exactly theirs, and those of no points are empty.
    ParticleSet ps;
    uint64_t seed = 5;
    auto next = [&] {
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        return float(double(seed >> 40) / double(1 << 24)) * 2.f - 1.f; // [-1, 1)
    };
    for (int i = 0; i < 300001; ++i)
        ps.positions.push_back(Vec3f(next(), next(), next()));
    ps.positions[7].x = -3.5f, ps.positions[299999].x = 2.25f;
    ps.positions[70000].y = -1.75f, ps.positions[150000].y = 4.f;
    ps.positions[300000].z = -8.f, ps.positions[200000].z = 1.5f;
    const BBox3f b = ps.bbox();
    EXPECT_EQ(b.min, Vec3f(-3.5f, -1.75f, -8.f));
    EXPECT_EQ(b.max, Vec3f(2.25f, 4.f, 1.5f));
    EXPECT_TRUE(boundsOf(ps.positions.data(), 0).empty());
    const BBox3f one = boundsOf(&ps.positions[70000], 1);
    EXPECT_EQ(one.min, ps.positions[70000]);
    EXPECT_EQ(one.max, ps.positions[70000]);
}
