// Round trips through every writable particle format: positions bit-exact, attributes intact.
#include "TestData.h"

#include <fluidsurf/Error.h>

#include <algorithm>
#include <cstring>
#include <random>
#include <tuple>

using namespace fluidsurf;
using namespace fluidsurf::test;

namespace {

/// Awkward values on purpose: mixed magnitudes and signs, values that are not short decimals.
ParticleSet awkwardParticles(size_t n)
{
    std::mt19937 rng(42);
    std::uniform_real_distribution<float> u(-1.f, 1.f);
    ParticleSet ps;
    std::vector<float> density, vel;
    std::vector<int64_t> id;
    for (size_t i = 0; i < n; ++i) {
        const float scale = std::pow(10.f, float(int(i % 7) - 3)); // 1e-3 .. 1e3
        ps.positions.emplace_back(u(rng) * scale, u(rng) * 3.f + 0.1f, u(rng) * 1000.f);
        density.push_back(1000.f + u(rng));
        for (int c = 0; c < 3; ++c)
            vel.push_back(u(rng) * 5.f);
        id.push_back(i % 3 == 0 ? -int64_t(i) : int64_t(2147483647 - i));
    }
    ps.addFloat("density", 1, density);
    ps.addFloat("v", 3, vel);
    ps.addInt("id", 1, id);
    return ps;
}

uint32_t bits(float f)
{
    uint32_t u;
    std::memcpy(&u, &f, 4);
    return u;
}

/// One particle as a comparable row of bit patterns.
std::vector<int64_t> row(const ParticleSet& ps, size_t i, bool withAttributes)
{
    std::vector<int64_t> r = {bits(ps.positions[i].x), bits(ps.positions[i].y),
                              bits(ps.positions[i].z)};
    if (!withAttributes) return r;
    for (const char* name : {"density", "v", "id"}) {
        const Attribute* a = ps.find(name);
        if (!a) return {};
        for (int c = 0; c < a->components; ++c)
            r.push_back(a->type == AttributeType::Float
                            ? int64_t(bits(a->floats[i * a->components + c]))
                            : a->ints[i * a->components + c]);
    }
    return r;
}

void expectSameParticles(const ParticleSet& a, const ParticleSet& b, bool withAttributes,
                         bool ordered)
{
    ASSERT_EQ(a.size(), b.size());
    std::vector<std::vector<int64_t>> ra, rb;
    for (size_t i = 0; i < a.size(); ++i) {
        ra.push_back(row(a, i, withAttributes));
        rb.push_back(row(b, i, withAttributes));
        ASSERT_FALSE(rb.back().empty()) << "an attribute was lost";
    }
    if (!ordered) {
        std::sort(ra.begin(), ra.end());
        std::sort(rb.begin(), rb.end());
    }
    for (size_t i = 0; i < ra.size(); ++i)
        ASSERT_EQ(ra[i], rb[i]) << "particle " << i;
}

struct Case
{
    const char* ext;
    bool attributes, ordered;
    /// particles: the writers encode 8,192 a chunk and 32 chunks a block (the .vdb's writer is
    /// OpenVDB's), so theirs cross blocks and end in a part-filled one
    size_t count = 5000;
};

class RoundTrip : public ::testing::TestWithParam<Case>
{
};

} // namespace

TEST_P(RoundTrip, PositionsBitExactAttributesIntact)
{
    const Case c = GetParam();
    TempDir dir;
    const ParticleSet original = awkwardParticles(c.count);
    const std::string path = dir.path(std::string("frame") + c.ext);
    io::writeParticles(original, path);
    const ParticleSet back = io::readParticles(path);
    expectSameParticles(original, back, c.attributes, c.ordered);
    if (c.attributes) {
        EXPECT_EQ(back.find("v")->components, 3);
        EXPECT_EQ(back.find("id")->type, AttributeType::Int);
    }
}

INSTANTIATE_TEST_SUITE_P(Formats, RoundTrip,
                         ::testing::Values(Case{".bgeo", true, true, 300001},
                                           Case{".bgeo.gz", true, true, 300001},
                                           Case{".ply", true, true, 300001},
                                           Case{".vtk", true, true, 300001},
                                           Case{".xyz", false, true, 300001},
                                           // VDB buckets points by voxel: same particles, any order
                                           Case{".vdb", true, false}),
                         [](const auto& info) {
                             std::string n = info.param.ext + 1;
                             std::replace(n.begin(), n.end(), '.', '_');
                             return n;
                         });

TEST(RoundTrip, Int64IdsSurviveVtkAndVdbButBgeoRefusesThem)
{
    TempDir dir;
    ParticleSet ps;
    ps.positions = {{0, 0, 0}, {1, 1, 1}};
    ps.addInt("id", 1, {int64_t(1) << 40, -5});
    for (const char* ext : {".vtk", ".vdb"}) {
        io::writeParticles(ps, dir.path(std::string("a") + ext));
        const ParticleSet back = io::readParticles(dir.path(std::string("a") + ext));
        std::vector<int64_t> ids = back.find("id")->ints;
        std::sort(ids.begin(), ids.end());
        EXPECT_EQ(ids, (std::vector<int64_t>{-5, int64_t(1) << 40})) << ext;
    }
    EXPECT_THROW(io::writeParticles(ps, dir.path("a.bgeo")), OutputError);
    EXPECT_FALSE(fileExists(dir.path("a.bgeo")));
}

TEST(RoundTrip, FailedWriteKeepsTheExistingFileAndLeavesNoTemporary)
{
    TempDir dir;
    const std::string path = dir.path("keep.bgeo");
    writeFile(path, "precious");
    ParticleSet ps;
    ps.positions = {{0, 0, 0}};
    ps.addInt("id", 1, {int64_t(1) << 40});
    EXPECT_THROW(io::writeParticles(ps, path), OutputError);
    EXPECT_EQ(readFileBytes(path), "precious");
    EXPECT_THROW(io::writeParticles(ps, dir.path("no/such/folder/x.ply")), OutputError);
    const std::string listing = dir.path();
    int entries = 0;
    for (const char* probe : {"keep.bgeo"})
        entries += fileExists(dir.path(probe));
    EXPECT_EQ(entries, 1);
    EXPECT_EQ(std::system(("test $(ls -A '" + listing + "' | wc -l) -eq 1").c_str()), 0)
        << "temporary file left behind";
}
