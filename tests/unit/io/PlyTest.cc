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

TEST(Ply, ManyBinaryVerticesOfMixedTypesInEitherByteOrder)
{
    // more vertices than one of the reader's parallel ranges (16,384) and than one slice of the
    // file (1 MiB), properties of every size around the coordinates, values chosen per vertex so
    // that a value read from the wrong vertex or the wrong place in it shows. Read from memory
    // and from a file, after no element, an element of fixed size (the file read finds the
    // vertices past it) and one with a list (the file is then read whole); an element after
    // them, which is left.
    const uint32_t n = 70001;
    const test::TempDir dir;
    for (const bool big : {true, false})
        for (const std::string before : {"", "fixed", "list"}) {
            SCOPED_TRACE(std::string(big ? "big-endian" : "little-endian") + ", before: " + before);
            ByteBuilder b;
            b.text(std::string("ply\nformat ") +
                   (big ? "binary_big_endian" : "binary_little_endian") + " 1.0\n");
            if (before == "fixed") b.text("element camera 3\nproperty float a\nproperty uchar b\n");
            if (before == "list")
                b.text("element face 2\nproperty list uchar int vertex_indices\n");
            b.text("element vertex " + std::to_string(n) +
                   "\nproperty uchar flag\nproperty double x\nproperty short t\nproperty float "
                   "y\nproperty uint id\nproperty double z\nproperty float v_0\nproperty float "
                   "v_1\nproperty char s\nelement tail 1\nproperty int q\nend_header\n");
            auto put = [&](auto v) { big ? b.be(v) : b.le(v); };
            for (int k = 0; k < 3 && before == "fixed"; ++k)
                put(float(k)), put(uint8_t(k));
            if (before == "list") put(uint8_t(3)), put(0), put(1), put(2), put(uint8_t(1)), put(5);
            for (uint32_t i = 0; i < n; ++i) {
                put(uint8_t(i % 251));
                put(double(i) * 1e-3 + 1.0 / 3);
                put(int16_t(int(i % 60000) - 30000));
                put(-float(i) * 0.25f);
                put(4000000000u - i);
                put(1e10 - double(i));
                put(float(i) + 0.5f);
                put(-float(i));
                put(int8_t(int(i % 256) - 128));
            }
            put(9); // the tail, which the reader leaves
            for (const auto& [way, ps] :
                 readFromMemoryAndFile(b.s, ParticleFormat::Ply, dir.path("many.ply"))) {
                SCOPED_TRACE(way);
                ASSERT_EQ(ps.size(), n);
                const Attribute *flag = ps.find("flag"), *t = ps.find("t"), *id = ps.find("id"),
                                *v = ps.find("v"), *s = ps.find("s");
                ASSERT_TRUE(flag && t && id && v && s);
                ASSERT_EQ(v->components, 2);
                size_t bad = 0;
                for (uint32_t i = 0; i < n; ++i) {
                    const Vec3f p(float(double(i) * 1e-3 + 1.0 / 3), -float(i) * 0.25f,
                                  float(1e10 - double(i)));
                    bad += ps.positions[i] != p;
                    bad += flag->ints[i] != int64_t(i % 251);
                    bad += t->ints[i] != int64_t(i % 60000) - 30000;
                    bad += id->ints[i] != int64_t(4000000000u - i);
                    bad += v->floats[2 * i] != float(i) + 0.5f || v->floats[2 * i + 1] != -float(i);
                    bad += s->ints[i] != int64_t(i % 256) - 128;
                }
                EXPECT_EQ(bad, 0u);
            }
            // cut 10 bytes into the last vertex: the whole file's message, either way
            writeFile(dir.path("cut.ply"), b.s.substr(0, b.s.size() - 4 - 26));
            try {
                io::readParticles(dir.path("cut.ply"));
                ADD_FAILURE() << "a cut file was read";
            } catch (const InputError& e) {
                EXPECT_NE(std::string(e.what()).find("header promises 70001 vertices (36 bytes "
                                                     "each) but only 2520010 bytes remain"),
                          std::string::npos)
                    << e.what();
            }
        }
}
