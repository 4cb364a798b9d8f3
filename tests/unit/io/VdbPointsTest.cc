// OpenVDB points: the file is a real PointDataGrid that OpenVDB itself reads back.
#include "TestData.h"

#include <openvdb/openvdb.h>
#include <openvdb/points/PointCount.h>
#include <openvdb/points/PointDataGrid.h>

using namespace fluidsurf;
using namespace fluidsurf::test;

TEST(VdbPoints, WrittenGridIsAPointDataGridWithAttributes)
{
    TempDir dir;
    ParticleSet ps;
    for (int i = 0; i < 1000; ++i)
        ps.positions.emplace_back(0.01f * i, 0.02f * (i % 10), -0.5f);
    std::vector<float> rho(1000, 1000.f);
    ps.addFloat("density", 1, rho);
    ps.addFloat("v", 3, std::vector<float>(3000, 0.5f));
    io::writeParticles(ps, dir.path("p.vdb"));

    openvdb::initialize();
    openvdb::io::File file(dir.path("p.vdb"));
    file.open();
    auto grids = file.getGrids();
    file.close();
    ASSERT_EQ(grids->size(), 1u);
    auto grid = openvdb::gridPtrCast<openvdb::points::PointDataGrid>((*grids)[0]);
    ASSERT_TRUE(grid);
    EXPECT_EQ(openvdb::points::pointCount(grid->tree()), 1000u);
    const auto& desc = grid->tree().cbeginLeaf()->attributeSet().descriptor();
    EXPECT_NE(desc.find("density"), openvdb::points::AttributeSet::INVALID_POS);
    EXPECT_EQ(desc.type(desc.find("v")).first, "vec3s");
}

TEST(VdbPoints, LevelSetOnlyFileIsAClearError)
{
    TempDir dir;
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(1.f);
    grid->setName("surface");
    openvdb::io::File(dir.path("ls.vdb")).write({grid});
    try {
        io::readParticles(dir.path("ls.vdb"));
        FAIL() << "no error";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("no PointDataGrid"), std::string::npos) << e.what();
        EXPECT_NE(std::string(e.what()).find("surface"), std::string::npos) << e.what();
    }
}

TEST(VdbPoints, TruncatedFileIsCaughtBeforeOpenVdbReadsIt)
{
    // OpenVDB itself allocated gigabytes on such files; the structural pre-check names the cut.
    TempDir dir;
    ParticleSet ps;
    for (int i = 0; i < 500; ++i)
        ps.positions.emplace_back(0.1f * i, 0.f, 0.f);
    io::writeParticles(ps, dir.path("p.vdb"));
    const std::string bytes = readFileBytes(dir.path("p.vdb"));
    const std::string msg =
        readError(bytes.substr(0, bytes.size() / 2), io::ParticleFormat::VdbPoints);
    EXPECT_NE(msg.find("bytes (truncated file?)"), std::string::npos) << msg;
}

namespace {
std::string writtenVdb(TempDir& dir)
{
    ParticleSet ps;
    for (int i = 0; i < 500; ++i)
        ps.positions.emplace_back(0.1f * i, 0.f, 0.f);
    io::writeParticles(ps, dir.path("p.vdb"));
    return readFileBytes(dir.path("p.vdb"));
}
void putLE32(std::string& s, size_t at, uint32_t v)
{
    std::memcpy(&s[at], &v, 4);
}
} // namespace

TEST(VdbPoints, CorruptGridMetadataLengthIsCaughtBeforeOpenVdb)
{
    // OpenVDB sized a multi-gigabyte string from such a field (found by fuzz_vdb).
    TempDir dir;
    std::string bytes = writtenVdb(dir);
    const size_t name = bytes.find("file_bbox_max");
    ASSERT_NE(name, std::string::npos);
    putLE32(bytes, name - 4, 0x7ffffff0u);
    const std::string msg = readError(bytes, io::ParticleFormat::VdbPoints);
    EXPECT_NE(msg.find("metadata name"), std::string::npos) << msg;
}

TEST(VdbPoints, CorruptRootTileCountIsCaughtBeforeOpenVdb)
{
    // OpenVDB looped for minutes on a huge root tile count (found by fuzz_vdb).
    TempDir dir;
    std::string bytes = writtenVdb(dir);
    const size_t map = bytes.find("UniformScaleMap");
    ASSERT_NE(map, std::string::npos);
    const size_t tree = map + 15 + 120; // map name, then the map's 5 Vec3d
    uint32_t buffers;
    std::memcpy(&buffers, &bytes[tree], 4);
    ASSERT_EQ(buffers, 1u) << "layout assumption: tree buffer count follows the transform";
    putLE32(bytes, tree + 8, 0xfffffff0u); // after buffer count and background
    const std::string msg = readError(bytes, io::ParticleFormat::VdbPoints);
    EXPECT_NE(msg.find("corrupt root node"), std::string::npos) << msg;
}
