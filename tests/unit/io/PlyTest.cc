// PLY reader: ascii, binary big-endian with double coordinates and an element before the
// vertices, and the regrouping of name_0..name_k properties.
#include "TestData.h"

using namespace fluidsurf;
using namespace fluidsurf::test;
using io::ParticleFormat;

TEST(Ply, AsciiWithExtraProperties)
{
    const std::string f =
        "ply\nformat ascii 1.0\ncomment hello\nelement vertex 2\nproperty float x\n"
        "property float y\nproperty float z\nproperty int id\nproperty float v_0\n"
        "property float v_1\nproperty float v_2\nend_header\n"
        "1 2 3 7 0.5 0.25 0\n-1 -2 -3.5 8 1 1 1\n";
    const ParticleSet ps = readBytes(f, ParticleFormat::Ply);
    ASSERT_EQ(ps.size(), 2u);
    EXPECT_EQ(ps.positions[1], Vec3f(-1.f, -2.f, -3.5f));
    EXPECT_EQ(ps.find("id")->ints, (std::vector<int64_t>{7, 8}));
    ASSERT_NE(ps.find(AttributeRole::Velocity), nullptr) << "v_0..v_2 regroup into the float3 'v'";
    EXPECT_EQ(ps.find("v")->floats[1], 0.25f);
}

TEST(Ply, BinaryBigEndianDoublesAfterAListElement)
{
    ByteBuilder b;
    b.text("ply\r\nformat binary_big_endian 1.0\r\nelement face 2\r\nproperty list uchar int "
           "vertex_indices\r\n"
           "element vertex 2\r\nproperty double x\r\nproperty double y\r\nproperty double z\r\n"
           "property uchar red\r\nend_header\n");
    b.be(uint8_t(3)).be(int32_t(0)).be(int32_t(1)).be(int32_t(0));
    b.be(uint8_t(2)).be(int32_t(1)).be(int32_t(0));
    b.be(0.1).be(0.2).be(0.3).be(uint8_t(255));
    b.be(1e-30).be(-5.0).be(6.0).be(uint8_t(7));
    const ParticleSet ps = readBytes(b.s, ParticleFormat::Ply);
    ASSERT_EQ(ps.size(), 2u);
    EXPECT_EQ(ps.positions[0], Vec3f(float(0.1), float(0.2), float(0.3)));
    EXPECT_EQ(ps.positions[1], Vec3f(float(1e-30), -5.f, 6.f));
    EXPECT_EQ(ps.find("red")->ints, (std::vector<int64_t>{255, 7}));
}

TEST(Ply, MissingCoordinatesNamed)
{
    const std::string f = "ply\nformat ascii 1.0\nelement vertex 1\nproperty float x\nproperty "
                          "float y\nend_header\n1 2\n";
    EXPECT_NE(readError(f, ParticleFormat::Ply).find("lacks x, y, z"), std::string::npos);
}
