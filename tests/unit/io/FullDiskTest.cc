// FullDiskTest.cc - every writer on a disk that fills up (issue 63): the write fails with an
// OutputError naming the output the user gave (not a hidden temporary), the older file under
// that name keeps its bytes, and no temporary is left. A full disk is made with RLIMIT_FSIZE:
// past the limit write(2) fails with EFBIG (SIGXFSZ ignored), as it fails with ENOSPC on a full
// file system, at the same calls.
#include "TestData.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/ParticleSet.h>
#include <fluidsurf/io/AtomicFile.h>
#include <fluidsurf/io/LevelSetIO.h>
#include <fluidsurf/io/MeshIO.h>
#include <fluidsurf/io/ParticleIO.h>

#include <gtest/gtest.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <dirent.h>
#include <signal.h>
#include <sys/resource.h>

#include <functional>
#include <string>

namespace fluidsurf {
namespace {

/// While it lives, no file of this process grows past bytes.
class FileSizeLimit
{
public:
    explicit FileSizeLimit(rlim_t bytes)
    {
        mOldHandler = ::signal(SIGXFSZ, SIG_IGN);
        ::getrlimit(RLIMIT_FSIZE, &mOld);
        struct rlimit limit = mOld;
        limit.rlim_cur = bytes;
        mSet = ::setrlimit(RLIMIT_FSIZE, &limit) == 0;
    }
    ~FileSizeLimit()
    {
        ::setrlimit(RLIMIT_FSIZE, &mOld);
        ::signal(SIGXFSZ, mOldHandler);
    }
    bool set() const { return mSet; }

private:
    struct rlimit mOld;
    void (*mOldHandler)(int);
    bool mSet = false;
};

size_t filesIn(const std::string& folder)
{
    size_t n = 0;
    if (DIR* d = ::opendir(folder.c_str())) {
        while (const dirent* e = ::readdir(d))
            n += std::string(e->d_name) != "." && std::string(e->d_name) != "..";
        ::closedir(d);
    }
    return n;
}

/// write(path) with 64 KiB of disk left: OutputError naming path, the old bytes kept, nothing
/// else in the folder. The same write without the limit succeeds (the output is large enough
/// to fill it).
void expectFullDiskKeepsOldFile(const std::string& name,
                                const std::function<void(const std::string&)>& write)
{
    SCOPED_TRACE(name);
    const test::TempDir dir;
    const std::string path = dir.path(name);
    test::writeFile(path, "the older, good file");
    {
        const FileSizeLimit limit(64 << 10);
        ASSERT_TRUE(limit.set());
        try {
            write(path);
            ADD_FAILURE() << "no error on a full disk";
        } catch (const OutputError& e) {
            const std::string what = e.what();
            EXPECT_EQ(what.compare(0, path.size(), path), 0) << what;
            EXPECT_EQ(what.find(".fluidsurf-"), std::string::npos) << what;
        }
    }
    EXPECT_EQ(test::readFileBytes(path), "the older, good file");
    EXPECT_EQ(filesIn(dir.path()), 1u) << "a temporary was left";
    write(path); // without the limit
    EXPECT_GT(test::readFileBytes(path).size(), size_t(64 << 10));
}

openvdb::GridPtrVec sphereGrid()
{
    openvdb::initialize();
    return {
        openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(60.0f, openvdb::Vec3f(0), 1.0f)};
}

ParticleSet cloud(size_t n)
{
    ParticleSet ps;
    for (size_t i = 0; i < n; ++i)
        ps.positions.push_back(
            Vec3f(float(i % 97) * 0.37f, float(i % 89) * 0.53f, float(i) * 1e-3f));
    return ps;
}

TriangleMesh strip(size_t n)
{
    TriangleMesh m;
    for (size_t i = 0; i < n; ++i) {
        m.points.push_back(Vec3f(float(i), 0, 0));
        m.points.push_back(Vec3f(float(i), 1, 0));
    }
    for (uint32_t i = 0; i + 1 < n; ++i) {
        m.triangles.push_back({2 * i, 2 * i + 2, 2 * i + 1});
        m.triangles.push_back({2 * i + 1, 2 * i + 2, 2 * i + 3});
    }
    return m;
}

// The .vdb writers went through OpenVDB's io::File, whose std::ofstream failures nobody checked:
// `rasterize -o f.vdb` on a full disk printed success and replaced f.vdb with a cut file.
TEST(FullDisk, LevelSetVdbKeepsTheOlderFile)
{
    const openvdb::GridPtrVec grids = sphereGrid();
    expectFullDiskKeepsOldFile("f.vdb", [&](const std::string& p) { io::writeLevelSet(grids, p); });
}

TEST(FullDisk, PointVdbKeepsTheOlderFile)
{
    const ParticleSet ps = cloud(40000);
    io::WriteOptions uncompressed;
    uncompressed.compress = false; // (Blosc would fit the cloud in the limit)
    expectFullDiskKeepsOldFile(
        "pts.vdb", [&](const std::string& p) { io::writeParticles(ps, p, uncompressed); });
}

TEST(FullDisk, ParticleFormatsKeepTheOlderFile)
{
    const ParticleSet ps = cloud(40000);
    for (const char* name : {"p.bgeo", "p.ply", "p.xyz", "p.vtk"})
        expectFullDiskKeepsOldFile(name, [&](const std::string& p) { io::writeParticles(ps, p); });
}

TEST(FullDisk, MeshFormatsKeepTheOlderFile)
{
    const TriangleMesh m = strip(20000);
    for (const char* name : {"m.obj", "m.ply", "m.vtk"})
        expectFullDiskKeepsOldFile(name, [&](const std::string& p) { io::writeMesh(m, p); });
}

TEST(FullDisk, StatsJsonKeepsTheOlderFile)
{
    const std::string json(200000, ' ');
    expectFullDiskKeepsOldFile(
        "s.json", [&](const std::string& p) { io::writeFileAtomic(p, json.data(), json.size()); });
}

// A frame's .vdb and mesh appear together: the mesh fails after the .vdb was written whole, and
// both older files stay. The error names the mesh the user asked for.
TEST(FullDisk, AnOutputGroupKeepsEveryOlderFile)
{
    const test::TempDir dir;
    test::writeFile(dir.path("f.vdb"), "old vdb");
    test::writeFile(dir.path("f.obj"), "old obj");
    const openvdb::GridPtrVec grids = sphereGrid();
    {
        const FileSizeLimit limit(4 << 20); // the sphere's .vdb fits, the mesh's OBJ does not
        ASSERT_TRUE(limit.set());
        try {
            io::OutputGroup group;
            io::writeLevelSet(grids, group.add(dir.path("f.vdb")));
            io::writeMesh(strip(120000), group.add(dir.path("f.obj")));
            group.commit();
            ADD_FAILURE() << "no error on a full disk";
        } catch (const OutputError& e) {
            EXPECT_EQ(std::string(e.what()).compare(0, dir.path("f.obj").size(), dir.path("f.obj")),
                      0)
                << e.what();
        }
    }
    EXPECT_EQ(test::readFileBytes(dir.path("f.vdb")), "old vdb");
    EXPECT_EQ(test::readFileBytes(dir.path("f.obj")), "old obj");
    EXPECT_EQ(filesIn(dir.path()), 2u);
}

} // namespace
} // namespace fluidsurf
