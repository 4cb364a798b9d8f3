// Mesh writers: a tetrahedron written as OBJ, PLY and VTK, parsed back independently.
#include "TestData.h"

#include <fluidsurf/io/MeshIO.h>

#include <sstream>

using namespace fluidsurf;
using namespace fluidsurf::test;

namespace {
TriangleMesh tetrahedron()
{
    TriangleMesh m;
    m.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    m.normals = {{-1, -1, -1}, {1, 0, 0}, {0, 1, 0}, {0, 0, 1}};
    m.triangles = {{0, 2, 1}, {0, 1, 3}, {0, 3, 2}, {1, 2, 3}};
    return m;
}
} // namespace

TEST(MeshIO, ObjHasVerticesNormalsAndOneBasedFaces)
{
    TempDir dir;
    io::writeMesh(tetrahedron(), dir.path("t.obj"));
    std::istringstream in(readFileBytes(dir.path("t.obj")));
    std::string line;
    std::vector<Vec3f> v;
    int vn = 0;
    std::vector<std::string> faces;
    while (std::getline(in, line)) {
        std::istringstream ls(line);
        std::string key;
        ls >> key;
        if (key == "v") {
            Vec3f p;
            ls >> p.x >> p.y >> p.z;
            v.push_back(p);
        }
        if (key == "vn") ++vn;
        if (key == "f") faces.push_back(line);
    }
    EXPECT_EQ(v, tetrahedron().points);
    EXPECT_EQ(vn, 4);
    ASSERT_EQ(faces.size(), 4u);
    EXPECT_EQ(faces[0], "f 1//1 3//3 2//2");
}

TEST(MeshIO, BinaryPlyLayout)
{
    TempDir dir;
    io::writeMesh(tetrahedron(), dir.path("t.ply"));
    const std::string s = readFileBytes(dir.path("t.ply"));
    const size_t end = s.find("end_header\n");
    ASSERT_NE(end, std::string::npos);
    const std::string header = s.substr(0, end);
    EXPECT_NE(header.find("element vertex 4"), std::string::npos);
    EXPECT_NE(header.find("property float nx"), std::string::npos);
    EXPECT_NE(header.find("element face 4"), std::string::npos);
    const size_t body = end + 11;
    ASSERT_EQ(s.size() - body, 4 * 24 + 4 * 13u);
    float y2;
    std::memcpy(&y2, s.data() + body + 2 * 24 + 4, 4);
    EXPECT_EQ(y2, 1.f);
    int32_t lastFace[3];
    std::memcpy(lastFace, s.data() + s.size() - 12, 12);
    EXPECT_EQ(lastFace[0], 1);
    EXPECT_EQ(lastFace[2], 3);
    // The particle reader reads a mesh PLY's vertices (face element after vertices is ignored).
    const ParticleSet pts = io::readParticles(dir.path("t.ply"));
    EXPECT_EQ(pts.positions, tetrahedron().points);
}

TEST(MeshIO, VtkPolydataReadsBackPointsAndNormals)
{
    TempDir dir;
    io::writeMesh(tetrahedron(), dir.path("t.vtk"));
    const ParticleSet pts = io::readParticles(dir.path("t.vtk"));
    EXPECT_EQ(pts.positions, tetrahedron().points);
    ASSERT_NE(pts.find("normals"), nullptr);
    EXPECT_EQ(pts.find("normals")->floats[0], -1.f);
    EXPECT_NE(readFileBytes(dir.path("t.vtk")).find("POLYGONS 4 16"), std::string::npos);
}

TEST(MeshIO, RejectsBadIndicesAndUnknownExtensions)
{
    TempDir dir;
    TriangleMesh m = tetrahedron();
    m.triangles.push_back({0, 1, 9});
    EXPECT_THROW(io::writeMesh(m, dir.path("bad.obj")), OutputError);
    EXPECT_FALSE(fileExists(dir.path("bad.obj")));
    EXPECT_THROW(io::writeMesh(tetrahedron(), dir.path("t.stl")), OutputError);
}
