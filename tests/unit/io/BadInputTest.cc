// Bad input, per reader: files cut short, wrong magic, headers that promise more points than
// the file holds, absurd counts, NaN/Inf coordinates, empty files and zero particles. Each must
// give an InputError naming the source (never a crash, a hang or a huge allocation).
#include "TestData.h"

#include <fluidsurf/Scenes.h>

#include <regex>

using namespace fluidsurf;
using namespace fluidsurf::test;
using io::ParticleFormat;

namespace {

ParticleSet smallSet(size_t n = 64)
{
    SceneParams p;
    p.count = n;
    ParticleSet ps = generateScene(Scene::Block, p);
    ps.addFloat("density", 1, std::vector<float>(ps.size(), 1000.f));
    return ps;
}

/// A valid file of each format, written through the library's writers where it has one and by
/// hand otherwise.
std::string validFile(ParticleFormat f, const ParticleSet& ps)
{
    TempDir dir;
    auto viaWriter = [&](const char* ext) {
        io::writeParticles(ps, dir.path(std::string("f") + ext));
        return readFileBytes(dir.path(std::string("f") + ext));
    };
    switch (f) {
    case ParticleFormat::Bgeo:
        return viaWriter(".bgeo");
    case ParticleFormat::Ply:
        return viaWriter(".ply");
    case ParticleFormat::VtkLegacy:
        return viaWriter(".vtk");
    case ParticleFormat::VdbPoints:
        return viaWriter(".vdb");
    case ParticleFormat::Xyz:
        return viaWriter(".xyz");
    case ParticleFormat::Npy: {
        std::string dict = "{'descr': '<f4', 'fortran_order': False, 'shape': (" +
                           std::to_string(ps.size()) + ", 3), }";
        while ((10 + dict.size() + 1) % 64)
            dict += ' ';
        dict += '\n';
        ByteBuilder b;
        b.text("\x93NUMPY").le(uint8_t(1)).le(uint8_t(0)).le(uint16_t(dict.size())).text(dict);
        for (const Vec3f& p : ps.positions)
            b.le(p.x).le(p.y).le(p.z);
        return b.s;
    }
    case ParticleFormat::VtkXml: {
        ByteBuilder data;
        data.le(uint32_t(ps.size() * 12));
        for (const Vec3f& p : ps.positions)
            data.le(p.x).le(p.y).le(p.z);
        return "<VTKFile type=\"PolyData\" version=\"0.1\" "
               "byte_order=\"LittleEndian\">\n<PolyData>\n<Piece NumberOfPoints=\"" +
               std::to_string(ps.size()) +
               "\">\n<Points><DataArray type=\"Float32\" NumberOfComponents=\"3\" "
               "format=\"appended\" offset=\"0\"/></Points>\n</Piece>\n</PolyData>\n<AppendedData "
               "encoding=\"raw\">_" +
               data.s + "</AppendedData>\n</VTKFile>\n";
    }
    case ParticleFormat::Csv: {
        std::string s = "x,y,z\n";
        for (const Vec3f& p : ps.positions)
            s += std::to_string(p.x) + "," + std::to_string(p.y) + "," + std::to_string(p.z) + "\n";
        return s;
    }
    default:
        return "";
    }
}

struct FormatCase
{
    ParticleFormat format;
    const char* name;
    bool binary; // a cut file must be an error (text may still parse as fewer particles)
};

const FormatCase kFormats[] = {
    {ParticleFormat::Bgeo, "bgeo", true},     {ParticleFormat::Ply, "ply", true},
    {ParticleFormat::VtkLegacy, "vtk", true}, {ParticleFormat::VtkXml, "vtu", true},
    {ParticleFormat::Npy, "npy", true},       {ParticleFormat::VdbPoints, "vdb", true},
    {ParticleFormat::Xyz, "xyz", false},      {ParticleFormat::Csv, "csv", false},
};

class BadInput : public ::testing::TestWithParam<FormatCase>
{
};

void expectInputError(const std::string& bytes, ParticleFormat f, const std::string& what)
{
    const std::string msg = readError(bytes, f);
    EXPECT_FALSE(msg.empty()) << what << ": read without error";
    EXPECT_EQ(msg.rfind("test-input", 0), 0u)
        << what << ": message does not name the source: " << msg;
}

} // namespace

TEST_P(BadInput, TruncatedAtSeveralOffsets)
{
    const FormatCase c = GetParam();
    const ParticleSet ps = smallSet();
    const std::string file = validFile(c.format, ps);
    ASSERT_EQ(readBytes(file, c.format).size(), ps.size()) << "the valid file must read";
    for (double frac : {0.0001, 0.01, 0.1, 0.3, 0.5, 0.75, 0.97}) {
        const size_t cut = std::max<size_t>(1, size_t(double(file.size()) * frac));
        const std::string part = file.substr(0, cut);
        if (c.binary || (c.format == ParticleFormat::Xyz && cut % 12)) {
            expectInputError(part, c.format, "cut at " + std::to_string(cut));
        } else {
            // Text cut at a line boundary is a shorter valid file; it must never grow.
            std::string msg = readError(part, c.format);
            if (msg.empty()) EXPECT_LT(readBytes(part, c.format).size(), ps.size());
        }
    }
    // the last byte(s) missing
    if (c.binary) expectInputError(file.substr(0, file.size() - 3), c.format, "3 bytes short");
}

TEST_P(BadInput, EmptyFile)
{
    EXPECT_NE(readError("", GetParam().format).find("empty"), std::string::npos);
}

TEST_P(BadInput, WrongMagic)
{
    const FormatCase c = GetParam();
    if (c.format == ParticleFormat::Xyz || c.format == ParticleFormat::Csv)
        GTEST_SKIP() << "no magic in this format";
    std::string file = validFile(c.format, smallSet());
    file[0] = 'Q';
    file[1] = 'Z';
    expectInputError(file, c.format, "wrong magic");
}

TEST_P(BadInput, ZeroParticles)
{
    const FormatCase c = GetParam();
    const std::string file = validFile(c.format, ParticleSet());
    io::ReadOptions allow;
    allow.allowEmpty = true;
    if (c.format == ParticleFormat::Xyz) {
        // Headerless: no particles is a 0-byte file, which cannot be told from a lost one, so it
        // is an error like every empty file, even where empty frames are allowed.
        EXPECT_NE(readError(file, c.format).find("file is empty"), std::string::npos);
        EXPECT_THROW(readBytes(file, c.format, allow), InputError);
        return;
    }
    if (c.format == ParticleFormat::Csv) {
        // The same for text: a header and no rows is an empty file, not an empty frame.
        EXPECT_NE(readError(file, c.format).find("a header and no data rows"), std::string::npos)
            << readError(file, c.format);
        EXPECT_THROW(readBytes(file, c.format, allow), InputError);
        return;
    }
    EXPECT_NE(readError(file, c.format).find("no particles"), std::string::npos)
        << readError(file, c.format);
    EXPECT_EQ(readBytes(file, c.format, allow).size(), 0u);
}

TEST_P(BadInput, NonFiniteCoordinatesRejectedOrDroppedWhenAsked)
{
    const FormatCase c = GetParam();
    ParticleSet ps = smallSet();
    ps.positions[3].y = NAN;
    ps.positions[10].z = INFINITY;
    if (c.format == ParticleFormat::VdbPoints) {
        // VDB cannot place a NaN point in a voxel: its writer refuses, naming the problem.
        TempDir dir;
        try {
            io::writeParticles(ps, dir.path("nan.vdb"));
            FAIL() << "wrote NaN points to VDB";
        } catch (const OutputError& e) {
            EXPECT_NE(std::string(e.what()).find("NaN/Inf"), std::string::npos) << e.what();
        }
        EXPECT_FALSE(fileExists(dir.path("nan.vdb")));
        return;
    }
    const std::string file = validFile(c.format, ps);
    const std::string msg = readError(file, c.format);
    EXPECT_NE(msg.find("2 particle(s) have NaN/Inf"), std::string::npos) << msg;
    EXPECT_NE(msg.find("particle 3"), std::string::npos) << msg;
    io::ReadOptions drop;
    drop.dropNonFinite = true;
    const ParticleSet back = readBytes(file, c.format, drop);
    EXPECT_EQ(back.size(), ps.size() - 2);
    for (const Attribute& a : back.attributes)
        EXPECT_EQ(a.size(), back.size() * a.components);
}

INSTANTIATE_TEST_SUITE_P(Readers, BadInput, ::testing::ValuesIn(kFormats),
                         [](const auto& info) { return std::string(info.param.name); });

// Headers that promise more (or absurdly many) points than the file holds.
TEST(BadInputHeaders, PromisedCountsBeyondTheData)
{
    const ParticleSet ps = smallSet();
    for (const char* count : {"65", "1099511627776", "18446744073709551615"}) {
        const std::string n = count;
        std::string vtk = validFile(ParticleFormat::VtkLegacy, ps);
        vtk = std::regex_replace(vtk, std::regex("POINTS 64 "), "POINTS " + n + " ");
        expectInputError(vtk, ParticleFormat::VtkLegacy, "vtk POINTS " + n);

        std::string ply = validFile(ParticleFormat::Ply, ps);
        ply = std::regex_replace(ply, std::regex("element vertex 64"), "element vertex " + n);
        expectInputError(ply, ParticleFormat::Ply, "ply vertex " + n);

        std::string vtu = validFile(ParticleFormat::VtkXml, ps);
        vtu = std::regex_replace(vtu, std::regex("NumberOfPoints=\"64\""),
                                 "NumberOfPoints=\"" + n + "\"");
        expectInputError(vtu, ParticleFormat::VtkXml, "vtu NumberOfPoints " + n);

        std::string npy = validFile(ParticleFormat::Npy, ps);
        npy = std::regex_replace(npy, std::regex("\\(64, 3\\)"), "(" + n + ", 3)");
        expectInputError(npy, ParticleFormat::Npy, "npy shape " + n);
    }
    // BGEO: the point count is a big-endian int32 at byte 9.
    for (uint32_t n : {65u, 0x7fffffffu, 0x80000000u}) {
        std::string bgeo = validFile(ParticleFormat::Bgeo, ps);
        for (int i = 0; i < 4; ++i)
            bgeo[9 + i] = char(n >> (24 - 8 * i));
        expectInputError(bgeo, ParticleFormat::Bgeo, "bgeo points " + std::to_string(n));
    }
}

TEST(BadInputHeaders, ExtensionAndContentDisagree)
{
    const std::string ply = validFile(ParticleFormat::Ply, smallSet());
    const std::string msg = readError(ply, ParticleFormat::Bgeo);
    EXPECT_NE(msg.find("the name says Houdini BGEO but the content is PLY"), std::string::npos)
        << msg;
}

TEST(BadInputHeaders, MissingFileAndFolder)
{
    TempDir dir;
    try {
        io::readParticles(dir.path("nope.bgeo"));
        FAIL();
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("nope.bgeo: cannot open"), std::string::npos);
    }
    EXPECT_THROW(io::readParticles(dir.path() + "/"), InputError);
    EXPECT_THROW(io::readParticles(dir.path("frame.unknown")), InputError);
}
