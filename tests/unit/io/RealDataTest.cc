// The real frames in ../shared/data/real (written by SPlisHSPlasH, splashsurf, meshio): exact
// particle counts and attributes as documented in ../shared/data/README.md.
#include "TestData.h"

#include <set>

using namespace fluidsurf;
using namespace fluidsurf::test;

namespace {
struct RealFile
{
    const char* name;
    size_t count;
    std::set<AttributeRole> roles;
};

const RealFile kFiles[] = {
    {"double_dam_break_frame_26_4732_particles.vtk",
     4732,
     {AttributeRole::Id, AttributeRole::Velocity}},
    {"dam_break_frame_9_6859_particles.bgeo",
     6859,
     {AttributeRole::Id, AttributeRole::Density, AttributeRole::Velocity}},
    {"dam_break_frame_23_24389_particles.bgeo", 24389, {}},
    {"hilbert_46843_particles.bgeo", 46843, {}},
    {"bunny_frame_14_7705_particles.vtk", 7706, {AttributeRole::Id, AttributeRole::Velocity}},
    {"cube_2366_particles.vtk", 2366, {}},
    {"free_particles_1000_particles.vtk", 1000, {}},
    {"ParticleData_Random_1000.vtk", 1000, {}},
    {"fluid_250_particles.vtu",
     250,
     {AttributeRole::Velocity, AttributeRole::Density, AttributeRole::Id}},
    {"fluid_encoded_250_particles.vtu",
     250,
     {AttributeRole::Velocity, AttributeRole::Density, AttributeRole::Id}},
    {"splishsplash_sphere_12394_particles.bgeo", 12394, {AttributeRole::Radius, AttributeRole::Id}},
    {"splishsplash_particle_grid_400_particles.bgeo",
     400,
     {AttributeRole::Id, AttributeRole::Velocity}},
};

class RealData : public ::testing::TestWithParam<RealFile>
{
};
} // namespace

TEST_P(RealData, ExactCountAndAttributes)
{
    FLUIDSURF_REQUIRE_SHARED_DATA();
    const RealFile f = GetParam();
    const ParticleSet ps = io::readParticles(sharedData() + "/real/" + f.name);
    EXPECT_EQ(ps.size(), f.count);
    for (AttributeRole r : f.roles)
        EXPECT_NE(ps.find(r), nullptr) << "missing " << roleName(r);
    const BBox3f box = ps.bbox();
    for (int a = 0; a < 3; ++a)
        EXPECT_LT(box.max[a] - box.min[a], 1e3f) << "implausible extent";
}

INSTANTIATE_TEST_SUITE_P(Frames, RealData, ::testing::ValuesIn(kFiles), [](const auto& info) {
    std::string n = info.param.name;
    for (char& c : n)
        if (!std::isalnum(uint8_t(c))) c = '_';
    return n;
});

TEST(RealData, BothVtuEncodingsHoldTheSameParticles)
{
    FLUIDSURF_REQUIRE_SHARED_DATA();
    const ParticleSet a = io::readParticles(sharedData() + "/real/fluid_250_particles.vtu");
    const ParticleSet b = io::readParticles(sharedData() + "/real/fluid_encoded_250_particles.vtu");
    ASSERT_EQ(a.size(), b.size());
    EXPECT_EQ(a.positions, b.positions);
    EXPECT_EQ(a.find("density")->floats, b.find("density")->floats);
    EXPECT_EQ(a.find("index")->ints, b.find("index")->ints);
}

TEST(RealData, SphereRadiusAttributeIsTheDocumentedRadius)
{
    FLUIDSURF_REQUIRE_SHARED_DATA();
    const ParticleSet ps =
        io::readParticles(sharedData() + "/real/splishsplash_sphere_12394_particles.bgeo");
    for (float r : ps.find(AttributeRole::Radius)->floats)
        ASSERT_FLOAT_EQ(r, 0.025f);
}

TEST(RealData, LargeFramesReadWhenPresent)
{
    FLUIDSURF_REQUIRE_SHARED_DATA();
    const std::string path = sharedData() + "/large/dam_obstacle_t0.50_398850_particles.vtk";
    if (!fileExists(path)) GTEST_SKIP() << path << " absent";
    const ParticleSet ps = io::readParticles(path);
    EXPECT_EQ(ps.size(), 398850u);
    EXPECT_NE(ps.find(AttributeRole::Velocity), nullptr); // "Vel"
    EXPECT_NE(ps.find(AttributeRole::Density), nullptr);  // "Rhop"
    EXPECT_NE(ps.find(AttributeRole::Id), nullptr);       // "Idp"
}
