// BGEO v5 reader: files assembled byte by byte in partio's layout, plain and gzip-compressed.
#include "TestData.h"

using namespace fluidsurf;
using namespace fluidsurf::test;
using io::ParticleFormat;

namespace {
ByteBuilder bgeoHeader(int32_t points, int32_t pointAttribs)
{
    ByteBuilder b;
    b.text("BgeoV")
        .be(int32_t(5))
        .be(points)
        .be(int32_t(0))
        .be(int32_t(0))
        .be(int32_t(0))
        .be(pointAttribs)
        .be(int32_t(0))
        .be(int32_t(0))
        .be(int32_t(0));
    return b;
}
void attrDef(ByteBuilder& b, const std::string& name, int16_t size, int32_t type)
{
    b.be(uint16_t(name.size())).text(name).be(size).be(type);
    for (int i = 0; i < size; ++i)
        b.be(int32_t(0));
}

std::string sampleBgeo()
{
    ByteBuilder b = bgeoHeader(2, 4);
    attrDef(b, "id", 1, 1);
    attrDef(b, "density", 1, 0);
    attrDef(b, "v", 3, 5);
    // string/index attribute: default index, then the string table
    b.be(uint16_t(4)).text("name").be(int16_t(1)).be(int32_t(4)).be(int32_t(2));
    b.be(uint16_t(3)).text("foo").be(uint16_t(3)).text("bar");
    for (int i = 0; i < 2; ++i) {
        b.be(1.5f * i).be(-2.f).be(3.25f + i).be(1.f); // x y z w
        b.be(int32_t(100 + i)).be(1000.f + i).be(0.5f).be(-0.5f).be(float(i)).be(int32_t(i));
    }
    b.be(uint8_t(0)).be(uint8_t(0xff));
    return b.s;
}

void expectSample(const ParticleSet& ps)
{
    ASSERT_EQ(ps.size(), 2u);
    EXPECT_EQ(ps.positions[1], Vec3f(1.5f, -2.f, 4.25f));
    ASSERT_NE(ps.find(AttributeRole::Id), nullptr);
    EXPECT_EQ(ps.find("id")->ints, (std::vector<int64_t>{100, 101}));
    EXPECT_EQ(ps.find(AttributeRole::Density)->floats, (std::vector<float>{1000.f, 1001.f}));
    ASSERT_NE(ps.find(AttributeRole::Velocity), nullptr);
    EXPECT_EQ(ps.find("v")->floats, (std::vector<float>{0.5f, -0.5f, 0.f, 0.5f, -0.5f, 1.f}));
    ASSERT_NE(ps.find("name"), nullptr);
    EXPECT_EQ(ps.find("name")->ints, (std::vector<int64_t>{0, 1}));
}
} // namespace

TEST(Bgeo, Uncompressed)
{
    expectSample(readBytes(sampleBgeo(), ParticleFormat::Bgeo));
}
TEST(Bgeo, Gzip)
{
    expectSample(readBytes(gzipBytes(sampleBgeo()), ParticleFormat::Bgeo));
}

TEST(Bgeo, RejectsOtherVersionsAndJsonGeometry)
{
    std::string f = sampleBgeo();
    f[8] = 6;
    EXPECT_NE(readError(f, ParticleFormat::Bgeo).find("version 6"), std::string::npos);
    EXPECT_NE(readError("{\"fileversion\":\"19.0\"}", ParticleFormat::Bgeo).find("JSON"),
              std::string::npos);
}

TEST(Bgeo, TruncatedGzipIsAnError)
{
    const std::string z = gzipBytes(sampleBgeo());
    EXPECT_NE(readError(z.substr(0, z.size() / 2), ParticleFormat::Bgeo).find("truncated"),
              std::string::npos);
}

namespace {
/// 200,003 points of 40-byte records (x y z w, id, density, v, and a name index): more than one
/// slice of every reading path (4 MiB inflated, 1 MiB from a file), cut inside a record. Then
/// the extra section, as partio ends a file. The names' string table holds `strings` strings of
/// 100 characters.
std::string manyPointsBgeo(int32_t points, int32_t strings = 2)
{
    ByteBuilder b = bgeoHeader(points, 4);
    attrDef(b, "id", 1, 1);
    attrDef(b, "density", 1, 0);
    attrDef(b, "v", 3, 5);
    b.be(uint16_t(4)).text("name").be(int16_t(1)).be(int32_t(4)).be(strings);
    for (int32_t s = 0; s < strings; ++s)
        b.be(uint16_t(100)).text(std::string(100, char('a' + s % 26)));
    for (int32_t i = 0; i < points; ++i) {
        b.be(0.5f * float(i)).be(-float(i % 977)).be(1e-3f * float(i % 31)).be(1.f);
        b.be(int32_t(7 * i - 5)).be(1000.f + float(i % 13)).be(float(i)).be(-0.25f).be(2.f);
        b.be(int32_t(i % 2));
    }
    b.be(uint8_t(0)).be(uint8_t(0xff));
    return b.s;
}

void expectManyPoints(const ParticleSet& ps, int32_t points)
{
    ASSERT_EQ(ps.size(), size_t(points));
    const auto& id = ps.find("id")->ints;
    const auto& density = ps.find("density")->floats;
    const auto& v = ps.find("v")->floats;
    const auto& name = ps.find("name")->ints;
    size_t wrong = 0;
    for (int32_t i = 0; i < points; ++i) {
        const Vec3f p(0.5f * float(i), -float(i % 977), 1e-3f * float(i % 31));
        wrong += ps.positions[i] != p || id[i] != 7 * i - 5 ||
                 density[i] != 1000.f + float(i % 13) || v[3 * i] != float(i) ||
                 v[3 * i + 1] != -0.25f || v[3 * i + 2] != 2.f || name[i] != i % 2;
    }
    EXPECT_EQ(wrong, 0u);
}
} // namespace

TEST(Bgeo, ManyPointsFromTheFileFromGzipAndFromGzipMembers)
{
    const int32_t points = 200003;
    const std::string file = manyPointsBgeo(points);
    const test::TempDir dir;
    writeFile(dir.path("many.bgeo"), file);
    expectManyPoints(io::readParticles(dir.path("many.bgeo")), points);
    expectManyPoints(readBytes(file, ParticleFormat::Bgeo), points);
    writeFile(dir.path("many.bgeo.gz"), gzipBytes(file));
    expectManyPoints(io::readParticles(dir.path("many.bgeo.gz")), points);
    // members one after the other, cut inside a record, as `cat a.gz b.gz` makes them
    const size_t cut = 3000017;
    writeFile(dir.path("members.bgeo.gz"),
              gzipBytes(file.substr(0, cut)) + gzipBytes(file.substr(cut)));
    expectManyPoints(io::readParticles(dir.path("members.bgeo.gz")), points);
    // a 7 MB string table: the header is found in a 16 MiB prefix, which holds the first
    // points of more than one slice
    const std::string longHeader = manyPointsBgeo(points, 70000);
    writeFile(dir.path("long.bgeo.gz"), gzipBytes(longHeader));
    expectManyPoints(io::readParticles(dir.path("long.bgeo.gz")), points);
    writeFile(dir.path("long.bgeo"), longHeader);
    expectManyPoints(io::readParticles(dir.path("long.bgeo")), points);
}

TEST(Bgeo, PointsCutShortAreNamedInEveryPath)
{
    // a whole gzip stream, a file and memory, each ending 100 bytes into the points' last slice
    const std::string file = manyPointsBgeo(200003);
    const std::string cut = file.substr(0, file.size() - 2 - 40 * 1000);
    const test::TempDir dir;
    writeFile(dir.path("cut.bgeo"), cut);
    writeFile(dir.path("cut.bgeo.gz"), gzipBytes(cut));
    for (const std::string name : {"cut.bgeo", "cut.bgeo.gz"}) {
        try {
            io::readParticles(dir.path(name));
            ADD_FAILURE() << name << " was read";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("header promises 200003 points (40 bytes each) "
                                                 "but only 7960120 bytes remain"),
                      std::string::npos)
                << e.what();
        }
    }
    EXPECT_NE(readError(cut, ParticleFormat::Bgeo).find("header promises 200003 points"),
              std::string::npos);
}
