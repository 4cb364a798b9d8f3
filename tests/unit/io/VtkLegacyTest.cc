// Legacy VTK reader: files written byte by byte here, in the layouts simulators produce.
#include "TestData.h"

using namespace fluidsurf;
using namespace fluidsurf::test;
using io::ParticleFormat;

TEST(VtkLegacy, AsciiPolydataWithScalarsVectorsAndField)
{
    const std::string file =
        "# vtk DataFile Version 3.0\nparticles\nASCII\nDATASET POLYDATA\n"
        "POINTS 3 float\n0 0 0  1.5 -2 3\n1e-3 2.5e2 -7\n"
        "VERTICES 3 6\n1 0\n1 1\n1 2\n"
        "POINT_DATA 3\nSCALARS density float 1\nLOOKUP_TABLE default\n1000 1001.5 999\n"
        "VECTORS vel float\n1 2 3 4 5 6 7 8 9\n"
        "FIELD FieldData 2\nid 1 3 int\n7 8 9\nextra 2 3 double\n0.5 1 1.5 2 2.5 3\n";
    const ParticleSet ps = readBytes(file, ParticleFormat::VtkLegacy);
    ASSERT_EQ(ps.size(), 3u);
    EXPECT_EQ(ps.positions[1], Vec3f(1.5f, -2.f, 3.f));
    EXPECT_EQ(ps.positions[2], Vec3f(1e-3f, 250.f, -7.f));
    ASSERT_NE(ps.find(AttributeRole::Density), nullptr);
    EXPECT_FLOAT_EQ(ps.find("density")->floats[1], 1001.5f);
    ASSERT_NE(ps.find(AttributeRole::Velocity), nullptr);
    EXPECT_EQ(ps.find("vel")->floats[5], 6.f);
    const Attribute* id = ps.find(AttributeRole::Id);
    ASSERT_NE(id, nullptr);
    EXPECT_EQ(id->type, AttributeType::Int);
    EXPECT_EQ(id->ints, (std::vector<int64_t>{7, 8, 9}));
    ASSERT_NE(ps.find("extra"), nullptr);
    EXPECT_EQ(ps.find("extra")->components, 2);
    EXPECT_FLOAT_EQ(ps.find("extra")->floats[5], 3.f);
}

TEST(VtkLegacy, BinaryUnstructuredGridDoublePointsCellsAndCellData)
{
    ByteBuilder b;
    b.text("# vtk DataFile Version 4.1\nSPlisHSPlasH particle data\nBINARY\nDATASET "
           "UNSTRUCTURED_GRID\nPOINTS 2 double\n");
    for (double v : {0.25, -1.0, 3.0, 1e10, 2.0, -0.0})
        b.be(v);
    b.text("\nCELLS 2 4\n");
    for (int32_t v : {1, 0, 1, 1})
        b.be(v);
    b.text("\nCELL_TYPES 2\n").be(int32_t(1)).be(int32_t(1));
    b.text("\nCELL_DATA 2\nSCALARS cellval float 1\nLOOKUP_TABLE default\n").be(1.f).be(2.f);
    b.text("\nPOINT_DATA 2\nSCALARS id unsigned_int 1\nLOOKUP_TABLE id_table\n")
        .be(uint32_t(4000000000u))
        .be(uint32_t(5));
    b.text("\nFIELD FieldData 1\nvelocity 3 2 float\n");
    for (float v : {1.f, 2.f, 3.f, 4.f, 5.f, 6.f})
        b.be(v);
    b.text("\n");
    const ParticleSet ps = readBytes(b.s, ParticleFormat::VtkLegacy);
    ASSERT_EQ(ps.size(), 2u);
    EXPECT_EQ(ps.positions[0], Vec3f(0.25f, -1.f, 3.f));
    EXPECT_EQ(ps.positions[1], Vec3f(1e10f, 2.f, -0.f));
    EXPECT_EQ(ps.find("cellval"), nullptr) << "cell data must not become a particle attribute";
    EXPECT_EQ(ps.find("id")->ints, (std::vector<int64_t>{4000000000ll, 5}));
    EXPECT_EQ(ps.find("velocity")->floats[3], 4.f);
}

TEST(VtkLegacy, Version5OffsetsConnectivityAndMetadata)
{
    ByteBuilder b;
    b.text("# vtk DataFile Version 5.1\nvtk output\nBINARY\nDATASET POLYDATA\nPOINTS 2 float\n");
    for (float v : {1.f, 2.f, 3.f, 4.f, 5.f, 6.f})
        b.be(v);
    b.text("\nMETADATA\nINFORMATION 0\n\nVERTICES 3 2\nOFFSETS vtktypeint64\n");
    for (int64_t v : {0, 1, 2})
        b.be(v);
    b.text("\nCONNECTIVITY vtktypeint64\n").be(int64_t(0)).be(int64_t(1));
    b.text("\nPOINT_DATA 2\nSCALARS rho double 1\nLOOKUP_TABLE default\n").be(1.5).be(2.5);
    b.text("\n");
    const ParticleSet ps = readBytes(b.s, ParticleFormat::VtkLegacy);
    ASSERT_EQ(ps.size(), 2u);
    EXPECT_EQ(ps.positions[1], Vec3f(4.f, 5.f, 6.f));
    EXPECT_EQ(ps.find(AttributeRole::Density)->floats, (std::vector<float>{1.5f, 2.5f}));
}

TEST(VtkLegacy, RejectsNonPointDatasetsAndMismatchedPointData)
{
    EXPECT_NE(
        readError(
            "# vtk DataFile Version 3.0\nx\nASCII\nDATASET STRUCTURED_POINTS\nDIMENSIONS 2 2 2\n",
            ParticleFormat::VtkLegacy)
            .find("not a point set"),
        std::string::npos);
    EXPECT_NE(
        readError("# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 1 float\n0 0 0\n"
                  "POINT_DATA 2\nSCALARS a float\n1 2\n",
                  ParticleFormat::VtkLegacy)
            .find("does not match POINTS"),
        std::string::npos);
    EXPECT_NE(
        readError(
            "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 2 float\n0 0 0 1 x 2\n",
            ParticleFormat::VtkLegacy)
            .find("is not a number"),
        std::string::npos);
}

namespace {
/// What reading a file by its path gives: the particles, or the message.
std::string readPathError(const std::string& path)
{
    try {
        io::readParticles(path);
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}
} // namespace

TEST(VtkLegacy, BinaryFileReadFromItsSectionsAsFromMemory)
{
    // 200,003 points: several slices of each array. Built byte by byte here, not by our writer:
    // cells before the point data, a METADATA line longer than the file's 64 KiB window, and a
    // FIELD array of int64.
    const uint32_t n = 200003;
    ByteBuilder b;
    b.text("# vtk DataFile Version 5.1\nwide\nBINARY\nDATASET UNSTRUCTURED_GRID\nPOINTS " +
           std::to_string(n) + " float\n");
    for (uint32_t i = 0; i < n; ++i)
        b.be(float(i) * 0.5f).be(-float(i)).be(float(i % 977) + 0.25f);
    b.text("\nMETADATA\nINFORMATION 1\nNAME " + std::string(100000, 'm') + "\n\nCELLS " +
           std::to_string(n + 1) + " " + std::to_string(n) + "\nOFFSETS vtktypeint64\n");
    for (uint32_t i = 0; i <= n; ++i)
        b.be(int64_t(i));
    b.text("\nCONNECTIVITY vtktypeint64\n");
    for (uint32_t i = 0; i < n; ++i)
        b.be(int64_t(i));
    b.text("\nCELL_TYPES " + std::to_string(n + 1) + "\n");
    for (uint32_t i = 0; i <= n; ++i)
        b.be(int32_t(1));
    b.text("\nPOINT_DATA " + std::to_string(n) + "\nSCALARS rho double 1\nLOOKUP_TABLE default\n");
    for (uint32_t i = 0; i < n; ++i)
        b.be(1000.0 + double(i) / 3);
    b.text("\nFIELD FieldData 1\nid 1 " + std::to_string(n) + " vtktypeint64\n");
    for (uint32_t i = 0; i < n; ++i)
        b.be(int64_t(i) * 1000000007);
    b.text("\n");
    TempDir dir;
    for (const auto& [way, ps] :
         readFromMemoryAndFile(b.s, ParticleFormat::VtkLegacy, dir.path("wide.vtk"))) {
        SCOPED_TRACE(way);
        ASSERT_EQ(ps.size(), n);
        const Attribute *rho = ps.find("rho"), *id = ps.find("id");
        ASSERT_TRUE(rho && id);
        size_t bad = 0;
        for (uint32_t i = 0; i < n; ++i) {
            bad += ps.positions[i] != Vec3f(float(i) * 0.5f, -float(i), float(i % 977) + 0.25f);
            bad += rho->floats[i] != float(1000.0 + double(i) / 3);
            bad += id->ints[i] != int64_t(i) * 1000000007;
        }
        EXPECT_EQ(bad, 0u);
    }
    // Cut inside the ids, inside the cells' offsets and inside the points: the
    // file gives the message that the same bytes in memory give.
    const size_t cells = b.s.find("\nCELLS ");
    for (const size_t keep : {b.s.size() - 13, cells + 1000, size_t(5000)}) {
        SCOPED_TRACE("cut at " + std::to_string(keep));
        const std::string cut = b.s.substr(0, keep);
        writeFile(dir.path("cut.vtk"), cut);
        const std::string fromFile = readPathError(dir.path("cut.vtk"));
        const std::string fromMemory = readError(cut, ParticleFormat::VtkLegacy);
        ASSERT_FALSE(fromMemory.empty());
        // the memory path names its source differently; the rest is the same
        EXPECT_EQ(fromFile.substr(fromFile.find(": ")), fromMemory.substr(fromMemory.find(": ")));
        EXPECT_NE(fromFile.find("(at byte "), std::string::npos) << fromFile;
    }
}

TEST(VtkLegacy, AsciiAndLongLinesFromAFile)
{
    TempDir dir;
    // ASCII values go through memory, as before; the header line limits hold for the file
    const std::string ascii =
        "# vtk DataFile Version 3.0\nx\nASCII\nDATASET POLYDATA\nPOINTS 2 float\n0 0 0 1 2 3\n";
    writeFile(dir.path("a.vtk"), ascii);
    const ParticleSet ps = io::readParticles(dir.path("a.vtk"));
    ASSERT_EQ(ps.size(), 2u);
    EXPECT_EQ(ps.positions[1], Vec3f(1.f, 2.f, 3.f));
    writeFile(dir.path("t.vtk"), "# vtk DataFile Version 3.0\n" + std::string(70000, 't') +
                                     "\nBINARY\nDATASET POLYDATA\nPOINTS 0 float\n");
    EXPECT_NE(readPathError(dir.path("t.vtk")).find("line too long in the title line (at byte 27)"),
              std::string::npos);
}
