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
