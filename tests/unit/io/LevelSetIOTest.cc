// LevelSetIOTest.cc - describing .vdb files (ours and OpenVDB's own sphere) and reading meshes
// back: the facts `fluidsurf info` prints, checked against the grids and meshes themselves.
#include "TestData.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/MeshLevelSet.h>
#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Scenes.h>
#include <fluidsurf/io/LevelSetIO.h>
#include <fluidsurf/io/MeshIO.h>

#include <openvdb/tools/LevelSetSphere.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <limits>

namespace fluidsurf {
namespace {

std::string meta(const io::GridDescription& g, const std::string& name)
{
    for (const auto& m : g.metadata)
        if (m.first == name) return m.second;
    return "<missing>";
}

TEST(LevelSetIO, DescribesOurLevelSet)
{
    SceneParams sp;
    sp.count = 3000;
    const RasterizeResult res =
        rasterizeParticles(generateScene(Scene::Ball, sp), Params::fromRadius(sp.radius), "ball");
    const test::TempDir dir;
    io::writeLevelSet({res.grid}, dir.path("ball.vdb"));
    const std::vector<io::GridDescription> d = io::describeVdb(dir.path("ball.vdb"));
    ASSERT_EQ(d.size(), 1u);
    EXPECT_EQ(d[0].name, "surface");
    EXPECT_EQ(d[0].gridClass, "level set");
    EXPECT_EQ(d[0].valueType, "float");
    EXPECT_DOUBLE_EQ(d[0].voxelSize[0], sp.radius);
    EXPECT_EQ(d[0].activeVoxels, res.grid->activeVoxelCount());
    EXPECT_EQ(d[0].leaves, res.grid->tree().leafCount());
    const openvdb::CoordBBox box = res.grid->evalActiveVoxelBoundingBox();
    for (int a = 0; a < 3; ++a) {
        EXPECT_EQ(d[0].bboxMin[a], box.min()[a]);
        EXPECT_EQ(d[0].bboxMax[a], box.max()[a]);
    }
    EXPECT_EQ(meta(d[0], "fluidsurf:source"), "ball");
    EXPECT_EQ(meta(d[0], "fluidsurf:particle_count"), std::to_string(res.stats.particles));
    EXPECT_NE(meta(d[0], "fluidsurf:particle_radius"), "<missing>");
}

TEST(LevelSetIO, DescribesOpenVdbsOwnSphere)
{
    openvdb::initialize();
    auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        2.0f, openvdb::Vec3f(1, 2, 3), 0.1f, 3.0f);
    sphere->setName("ball");
    const test::TempDir dir;
    io::writeLevelSet({sphere}, dir.path("sphere.vdb"));
    const std::vector<io::GridDescription> d = io::describeVdb(dir.path("sphere.vdb"));
    ASSERT_EQ(d.size(), 1u);
    EXPECT_EQ(d[0].name, "ball");
    EXPECT_EQ(d[0].gridClass, "level set");
    EXPECT_FLOAT_EQ(float(d[0].voxelSize[1]), 0.1f);
    EXPECT_EQ(d[0].activeVoxels, sphere->activeVoxelCount());
    // Index-space bounds of a sphere of 20 voxels around (10, 20, 30), +-3 voxels of band.
    EXPECT_NEAR(double(d[0].bboxMin[0]), 10 - 20 - 3, 1.0);
    EXPECT_NEAR(double(d[0].bboxMax[2]), 30 + 20 + 3, 1.0);
}

TEST(LevelSetIO, UuidIsTheHashOfTheBytesAfterIt)
{
    // The UUID in the header (bytes 21 to 56) is made from the file's content: two FNV-1a
    // streams over every byte after it, written here plainly over the file read whole. The
    // writer hashes the file a chunk of 4 MiB at a time: this file is larger, so the chunks'
    // seams are crossed. Equal grids give equal files; another grid another UUID.
    openvdb::initialize();
    auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        160.0f, openvdb::Vec3f(0, 0, 0), 1.0f, 3.0f);
    const test::TempDir dir;
    io::writeLevelSet({sphere}, dir.path("a.vdb"));
    io::writeLevelSet({sphere}, dir.path("b.vdb"));
    const std::string a = test::readFileBytes(dir.path("a.vdb")),
                      b = test::readFileBytes(dir.path("b.vdb"));
    ASSERT_GT(a.size(), size_t(5) << 20);
    EXPECT_EQ(a, b);
    constexpr size_t kAt = 21, kLength = 36;
    uint64_t h[2] = {0xcbf29ce484222325ull, 0x84222325cbf29ce4ull};
    for (size_t i = kAt + kLength; i < a.size(); ++i) {
        h[0] = (h[0] ^ uint8_t(a[i])) * 0x100000001b3ull;
        h[1] = (h[1] ^ uint8_t(a[i]) ^ 0x5a) * 0x100000001b3ull;
    }
    char uuid[40];
    std::snprintf(uuid, sizeof(uuid), "%08x-%04x-%04x-%04x-%012llx", unsigned(h[0] >> 32),
                  unsigned(h[0] >> 16) & 0xffff, (unsigned(h[0]) & 0x0fff) | 0x4000,
                  (unsigned(h[1] >> 48) & 0x3fff) | 0x8000,
                  (unsigned long long)(h[1] & 0xffffffffffffull));
    EXPECT_EQ(a.substr(kAt, kLength), std::string(uuid));
    auto other = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        161.0f, openvdb::Vec3f(0, 0, 0), 1.0f, 3.0f);
    io::writeLevelSet({other}, dir.path("c.vdb"));
    EXPECT_NE(test::readFileBytes(dir.path("c.vdb")).substr(kAt, kLength), a.substr(kAt, kLength));
}

TEST(LevelSetIO, CorruptVdbIsOneInputError)
{
    const test::TempDir dir;
    test::writeFile(dir.path("bad.vdb"), std::string(" BDV\0\0\0\0garbage", 15));
    EXPECT_THROW(io::describeVdb(dir.path("bad.vdb")), InputError);
    EXPECT_THROW(io::describeVdb(dir.path("missing.vdb")), InputError);
}

TEST(MeshReader, ObjAndPlyRoundTrip)
{
    SceneParams sp;
    sp.count = 3000;
    const RasterizeResult res =
        rasterizeParticles(generateScene(Scene::Drop, sp), Params::fromRadius(sp.radius));
    const TriangleMesh mesh = meshLevelSet(*res.grid);
    const test::TempDir dir;
    for (const char* name : {"m.obj", "m.ply"}) {
        io::writeMesh(mesh, dir.path(name));
        const TriangleMesh back = io::readMesh(dir.path(name));
        EXPECT_EQ(back.triangles, mesh.triangles) << name;
        EXPECT_EQ(back.points, mesh.points) << name; // shortest round-trip floats in OBJ
        EXPECT_EQ(back.normals.size(), mesh.normals.size()) << name;
        const MeshReport a = checkMesh(mesh), b = checkMesh(back);
        EXPECT_TRUE(b.watertight()) << name;
        EXPECT_EQ(a.components, b.components) << name;
        EXPECT_DOUBLE_EQ(a.volume, b.volume) << name;
    }
}

TEST(MeshReader, PolygonsAndNegativeIndices)
{
    const test::TempDir dir;
    // A unit cube: 6 quads, half of them with negative (relative) indices.
    test::writeFile(dir.path("cube.obj"),
                    "# cube\nv 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\n"
                    "v 0 0 1\nv 1 0 1\nv 1 1 1\nv 0 1 1\n"
                    "f 1 4 3 2\nf 5 6 7 8\nf 1 2 6 5\n"
                    "f -6 -5 -1 -2\nf 2/1 3/2 7/3 6/4\nf 1//1 5//1 8//1 4//1\n");
    const TriangleMesh m = io::readMesh(dir.path("cube.obj"));
    EXPECT_EQ(m.points.size(), 8u);
    EXPECT_EQ(m.triangles.size(), 12u);
    const MeshReport r = checkMesh(m);
    EXPECT_TRUE(r.watertight()) << describe(r);
    EXPECT_NEAR(r.volume, 1.0, 1e-12);
    // ASCII PLY of the same solid, one tetrahedron.
    test::writeFile(dir.path("tet.ply"), "ply\nformat ascii 1.0\nelement vertex 4\n"
                                         "property float x\nproperty float y\nproperty float z\n"
                                         "element face 4\nproperty list uchar int vertex_indices\n"
                                         "end_header\n0 0 0\n1 0 0\n0 1 0\n0 0 1\n"
                                         "3 0 2 1\n3 0 1 3\n3 0 3 2\n3 1 2 3\n");
    const MeshReport t = checkMesh(io::readMesh(dir.path("tet.ply")));
    EXPECT_TRUE(t.watertight()) << describe(t);
    EXPECT_NEAR(t.volume, 1.0 / 6, 1e-7);
}

TEST(MeshReader, BadMeshesAreOneInputError)
{
    const test::TempDir dir;
    auto message = [&](const std::string& name, const std::string& bytes) {
        test::writeFile(dir.path(name), bytes);
        try {
            io::readMesh(dir.path(name));
        } catch (const InputError& e) {
            return std::string(e.what());
        }
        return std::string("no error");
    };
    EXPECT_NE(message("a.obj", "v 0 0 0\nv 1 0 0\nf 1 2 3\n").find("line 3"), std::string::npos);
    EXPECT_NE(message("b.obj", "v 0 0 zero\n").find("not a number"), std::string::npos);
    // A binary PLY whose header promises more faces than the file holds.
    EXPECT_NE(message("c.ply", "ply\nformat binary_little_endian 1.0\nelement vertex 1000000\n"
                               "property float x\nproperty float y\nproperty float z\n"
                               "end_header\n\x01\x02")
                  .find("truncated"),
              std::string::npos);
    EXPECT_NE(message("d.ply", "not a ply\n").find("not a PLY file"), std::string::npos);
    EXPECT_THROW(io::readMesh(dir.path("missing.obj")), InputError);
    EXPECT_THROW(io::readMesh(dir.path("x.stl")), InputError);
}

// One NaN vertex turned every vertex of `post`'s output into NaN, one at 1e38 pulled most to the
// origin (issue 63): refused where read, naming the file and the vertex.
TEST(MeshReader, NonFiniteOrFarVerticesAreRefused)
{
    const test::TempDir dir;
    const std::string tetra = "v 0 0 0\nv 1 0 0\nv 0 1 0\nv 0 0 1\n"
                              "f 1 3 2\nf 1 2 4\nf 1 4 3\nf 2 3 4\n";
    test::writeFile(dir.path("ok.obj"), tetra);
    EXPECT_EQ(io::readMesh(dir.path("ok.obj")).points.size(), 4u);
    for (const char* bad : {"nan", "inf", "-inf", "1e38", "2e15"}) {
        std::string text = tetra;
        text.replace(text.find("v 1 0 0"), 7, std::string("v 1 ") + bad + " 0");
        const std::string path = dir.path(std::string("bad_") + bad + ".obj");
        test::writeFile(path, text);
        try {
            io::readMesh(path);
            ADD_FAILURE() << bad << ": no error";
        } catch (const InputError& e) {
            const std::string what = e.what();
            EXPECT_NE(what.find(path + ": vertex 2 of 4"), std::string::npos) << what;
            EXPECT_NE(what.find("must be finite and within"), std::string::npos) << what;
        }
    }
    // written meshes never hold one either
    TriangleMesh m = io::readMesh(dir.path("ok.obj"));
    m.points[3].z = NAN;
    EXPECT_THROW(io::writeMesh(m, dir.path("out.obj")), OutputError);
    EXPECT_FALSE(test::fileExists(dir.path("out.obj")));
}

// A level set with a NaN or Inf voxel or tile meshed to NaN/Inf vertices (issue 63): refused
// where read, naming the file, the grid and where.
TEST(LevelSetIO, NonFiniteValuesAreRefused)
{
    openvdb::initialize();
    const test::TempDir dir;
    const float nan = std::numeric_limits<float>::quiet_NaN(),
                inf = std::numeric_limits<float>::infinity();
    int k = 0;
    for (const bool tile : {false, true})
        for (const float bad : {nan, inf, -inf}) {
            auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
                10.0f, openvdb::Vec3f(0), 1.0f);
            if (tile)
                sphere->tree().addTile(1, openvdb::Coord(64, 0, 0), bad, false);
            else
                sphere->tree().setValueOnly(openvdb::Coord(10, 0, 0), bad);
            const std::string path = dir.path("bad" + std::to_string(k++) + ".vdb");
            io::writeLevelSet({sphere}, path);
            try {
                io::readLevelSet(path);
                ADD_FAILURE() << path << ": no error";
            } catch (const InputError& e) {
                const std::string what = e.what();
                EXPECT_NE(what.find(path + ": grid"), std::string::npos) << what;
                EXPECT_NE(what.find(tile ? "at the tile (64, 0, 0)" : "at the voxel (10, 0, 0)"),
                          std::string::npos)
                    << what;
            }
        }
}

} // namespace
} // namespace fluidsurf
