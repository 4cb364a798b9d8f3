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
