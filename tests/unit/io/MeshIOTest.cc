// Mesh writers: a tetrahedron written as OBJ, PLY and VTK, parsed back independently.
#include "TestData.h"

#include "io/ObjInParallel.h"

#include <fluidsurf/io/MeshIO.h>

#include <cmath>
#include <set>
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

    // in a mesh large enough to be checked in parallel: the message names the first bad index
    // in triangle order, not the largest
    TriangleMesh big = tetrahedron();
    for (uint32_t i = 0; i < 200000; ++i)
        big.triangles.push_back(big.triangles[i % 4]);
    big.triangles[150001][2] = 9;
    big.triangles[190000][0] = 12;
    try {
        io::writeMesh(big, dir.path("big.ply"));
        ADD_FAILURE() << "no error";
    } catch (const OutputError& e) {
        EXPECT_NE(std::string(e.what()).find("triangle refers to vertex 9 of 4"), std::string::npos)
            << e.what();
    }
    EXPECT_FALSE(fileExists(dir.path("big.ply")));
    big.triangles[150001][2] = 3, big.triangles[190000][0] = 0;
    EXPECT_NO_THROW(io::writeMesh(big, dir.path("big.ply")));
}

TEST(MeshIO, VertexAttributesAsPlyPropertiesAndVtkFieldArrays)
{
    TempDir dir;
    const TriangleMesh m = tetrahedron();
    std::vector<Attribute> attributes(2);
    attributes[0].name = "v", attributes[0].components = 3;
    for (int i = 0; i < 12; ++i)
        attributes[0].floats.push_back(0.5f * float(i));
    attributes[1].name = "id", attributes[1].type = AttributeType::Int;
    attributes[1].ints = {7, -3, 2147483647, 0};
    for (const char* name : {"t.ply", "t.vtk"}) {
        io::writeMesh(m, dir.path(name), attributes);
        // read back by the particle reader, which knows nothing of meshes
        const ParticleSet back = io::readParticles(dir.path(name));
        EXPECT_EQ(back.positions, m.points) << name;
        const Attribute* id = back.find("id");
        ASSERT_NE(id, nullptr) << name;
        EXPECT_EQ(id->ints, attributes[1].ints) << name;
        if (std::string(name) == "t.vtk") {
            ASSERT_NE(back.find("v"), nullptr);
            EXPECT_EQ(back.find("v")->floats, attributes[0].floats);
        } else {
            for (int c = 0; c < 3; ++c) {
                const Attribute* vc = back.find(std::string("v") + "xyz"[c]);
                ASSERT_NE(vc, nullptr) << c;
                for (int i = 0; i < 4; ++i)
                    EXPECT_EQ(vc->floats[size_t(i)], attributes[0].floats[size_t(3 * i + c)]);
            }
            // and the mesh reader still reads the mesh, naming what it leaves out
            std::vector<std::string> dropped;
            const TriangleMesh read = io::readMesh(dir.path(name), &dropped);
            EXPECT_EQ(dropped, (std::vector<std::string>{"vx", "vy", "vz", "id"}));
            EXPECT_EQ(read.triangles, m.triangles);
            EXPECT_EQ(read.normals, m.normals);
        }
    }
    EXPECT_THROW(io::writeMesh(m, dir.path("t.obj"), attributes), OutputError);
    attributes[1].ints[0] = int64_t(1) << 40;
    EXPECT_THROW(io::writeMesh(m, dir.path("big.ply"), attributes), OutputError);
    attributes[1].ints.pop_back();
    EXPECT_THROW(io::writeMesh(m, dir.path("short.ply"), attributes), OutputError);
    EXPECT_FALSE(fileExists(dir.path("t.obj")) || fileExists(dir.path("big.ply")) ||
                 fileExists(dir.path("short.ply")));
}

namespace {

/// The legacy VTK file's bytes, read as the format says, apart from the writer: each section's
/// header line, then its big-endian 32-bit values.
class VtkBytes
{
public:
    explicit VtkBytes(std::string bytes) : mS(std::move(bytes)) {}
    /// The next line, without its '\n'.
    std::string line()
    {
        const size_t end = mS.find('\n', mAt);
        EXPECT_NE(end, std::string::npos);
        std::string l = mS.substr(mAt, end - mAt);
        mAt = end + 1;
        return l;
    }
    uint32_t value()
    {
        EXPECT_LE(mAt + 4, mS.size());
        const auto* b = reinterpret_cast<const unsigned char*>(mS.data() + mAt);
        mAt += 4;
        return uint32_t(b[0]) << 24 | uint32_t(b[1]) << 16 | uint32_t(b[2]) << 8 | uint32_t(b[3]);
    }
    float real()
    {
        const uint32_t b = value();
        float f;
        std::memcpy(&f, &b, 4);
        return f;
    }
    bool atEnd() const { return mAt == mS.size(); }

private:
    std::string mS;
    size_t mAt = 0;
};

} // namespace

TEST(MeshIO, VtkValuesBigEndianAcrossTheWritersBlocks)
{
    // more items than one block of the parallel writer (32 chunks of 8,192), a last block cut
    // short; with and without normals, with and without attributes
    TriangleMesh m;
    const uint32_t np = 300007, nt = 600011;
    for (uint32_t i = 0; i < np; ++i)
        m.points.push_back({float(i) * 0.5f, -float(i) / 7.f, 1e-20f * float(i + 1)});
    for (uint32_t i = 0; i < nt; ++i)
        m.triangles.push_back({i % np, (i * 7 + 1) % np, (np - 1 - i % np)});
    std::vector<Attribute> attributes(2);
    attributes[0].name = "v", attributes[0].components = 3;
    for (uint32_t i = 0; i < 3 * np; ++i)
        attributes[0].floats.push_back(float(i) - 1e6f);
    attributes[1].name = "id", attributes[1].type = AttributeType::Int;
    for (uint32_t i = 0; i < np; ++i)
        attributes[1].ints.push_back(int64_t(i) * 7919 - 1000000000);
    TempDir dir;
    for (int variant = 0; variant < 4; ++variant) {
        SCOPED_TRACE(variant);
        if (variant == 2) // normals from here on
            for (uint32_t i = 0; i < np; ++i)
                m.normals.push_back({0.f, float(i), -float(i)});
        const bool withAttributes = variant % 2 == 1;
        const std::vector<Attribute> with = withAttributes ? attributes : std::vector<Attribute>();
        io::writeMesh(m, dir.path("m.vtk"), with);
        VtkBytes in(readFileBytes(dir.path("m.vtk")));
        EXPECT_EQ(in.line(), "# vtk DataFile Version 4.2");
        EXPECT_EQ(in.line(), "fluidsurf mesh");
        EXPECT_EQ(in.line(), "BINARY");
        EXPECT_EQ(in.line(), "DATASET POLYDATA");
        EXPECT_EQ(in.line(), "POINTS 300007 float");
        size_t bad = 0;
        for (const Vec3f& p : m.points)
            bad += in.real() != p.x || in.real() != p.y || in.real() != p.z;
        EXPECT_EQ(in.line(), "");
        EXPECT_EQ(in.line(), "POLYGONS 600011 2400044");
        for (const auto& t : m.triangles)
            bad +=
                in.value() != 3 || in.value() != t[0] || in.value() != t[1] || in.value() != t[2];
        EXPECT_EQ(in.line(), "");
        if (variant > 0) EXPECT_EQ(in.line(), "POINT_DATA 300007");
        if (!m.normals.empty()) {
            EXPECT_EQ(in.line(), "NORMALS normals float");
            for (const Vec3f& n : m.normals)
                bad += in.real() != n.x || in.real() != n.y || in.real() != n.z;
            EXPECT_EQ(in.line(), "");
        }
        if (withAttributes) {
            EXPECT_EQ(in.line(), "FIELD FieldData 2");
            EXPECT_EQ(in.line(), "v 3 300007 float");
            for (float f : attributes[0].floats)
                bad += in.real() != f;
            EXPECT_EQ(in.line(), "");
            EXPECT_EQ(in.line(), "id 1 300007 int");
            for (int64_t k : attributes[1].ints)
                bad += int32_t(in.value()) != k;
            EXPECT_EQ(in.line(), "");
        }
        EXPECT_EQ(bad, 0u);
        EXPECT_TRUE(in.atEnd());
    }
}

TEST(MeshIO, BinaryPlyMeshesReadAsTheyLieOrItemByItem)
{
    // Large enough for several of the reader's parallel ranges (16,384 items), in either byte
    // order, with a property between the coordinates and normals in doubles; then with a quad
    // among the triangles and with an index past the points, which leave the parallel path.
    const uint32_t np = 40000, nt = 70001;
    auto point = [](uint32_t i) { return Vec3f(float(i), -0.5f * float(i), 1.f / float(i + 1)); };
    auto normal = [](uint32_t i) { return Vec3f(0.f, float(double(i) / 3), -float(i)); };
    auto triangle = [&](uint32_t t) {
        return std::array<uint32_t, 3>{t % np, (t * 13 + 5) % np, (np - 1) - t % np};
    };
    for (int variant = 0; variant < 4; ++variant) {
        SCOPED_TRACE(variant);
        const bool big = variant != 1;
        const uint32_t quadAt = variant == 2 ? 50000 : nt, badAt = variant == 3 ? 60000 : nt;
        ByteBuilder b;
        b.text(std::string("ply\nformat ") + (big ? "binary_big_endian" : "binary_little_endian") +
               " 1.0\nelement vertex " + std::to_string(np) +
               "\nproperty float x\nproperty uchar q\nproperty float y\nproperty float z\n"
               "property double nx\nproperty double ny\nproperty double nz\nelement face " +
               std::to_string(nt) + "\nproperty list uchar int vertex_indices\nend_header\n");
        auto put = [&](auto v) { big ? b.be(v) : b.le(v); };
        for (uint32_t i = 0; i < np; ++i) {
            const Vec3f p = point(i), n = normal(i);
            put(p.x), put(uint8_t(i)), put(p.y), put(p.z);
            put(double(n.x)), put(double(n.y)), put(double(n.z));
        }
        for (uint32_t t = 0; t < nt; ++t) {
            const auto tri = triangle(t);
            put(uint8_t(t == quadAt ? 4 : 3));
            put(int32_t(t == badAt ? np : tri[0])), put(int32_t(tri[1])), put(int32_t(tri[2]));
            if (t == quadAt) put(int32_t(7));
        }
        if (variant == 3) {
            try {
                io::readMeshFromMemory(reinterpret_cast<const uint8_t*>(b.s.data()), b.s.size(),
                                       io::MeshFormat::Ply, "m.ply");
                ADD_FAILURE() << "no error";
            } catch (const InputError& e) {
                EXPECT_NE(std::string(e.what()).find(
                              "m.ply: face vertex index 40000 outside the 40000 vertices"),
                          std::string::npos)
                    << e.what();
            }
            continue;
        }
        const TriangleMesh m = io::readMeshFromMemory(reinterpret_cast<const uint8_t*>(b.s.data()),
                                                      b.s.size(), io::MeshFormat::Ply, "m.ply");
        ASSERT_EQ(m.points.size(), np);
        ASSERT_EQ(m.normals.size(), np);
        size_t bad = 0;
        for (uint32_t i = 0; i < np; ++i)
            bad += m.points[i] != point(i) || m.normals[i] != normal(i);
        ASSERT_EQ(m.triangles.size(), variant == 2 ? nt + 1 : nt);
        for (uint32_t t = 0, k = 0; t < nt; ++t, ++k) {
            const auto tri = triangle(t);
            bad += m.triangles[k] != tri;
            if (t == quadAt) // fanned: (a, b, c), (a, c, 7)
                bad += m.triangles[++k] != std::array<uint32_t, 3>{tri[0], tri[2], 7};
        }
        EXPECT_EQ(bad, 0u);
    }
}

TEST(MeshIO, LargeObjReadAsOneThreadReadsIt)
{
    // Several of the reader's 1 MiB pieces: vertices interleaved with faces that reach back
    // across pieces by negative indices, quads, a/b/c and a//c corners, CRLF line ends,
    // comments, texture coordinates and vertex colours; normals one per vertex or not.
    const uint32_t np = 60000;
    for (const bool normalsForAll : {true, false}) {
        SCOPED_TRACE(normalsForAll);
        std::string f = "# made by the test\r\n";
        std::vector<Vec3f> points, normals;
        std::vector<std::array<uint32_t, 3>> triangles;
        for (uint32_t i = 0; i < np; ++i) {
            const Vec3f p(float(i) * 0.125f, -float(i), 1.f / float(i + 3));
            points.push_back(p);
            f += "v " + std::to_string(p.x) + " " + std::to_string(p.y) + "  " +
                 std::to_string(p.z) + " 0.5 0.5 0.5\r\n";
            // (std::to_string prints 6 decimals: the expected point is what that text reads as)
            points.back() = Vec3f(std::stof(std::to_string(p.x)), std::stof(std::to_string(p.y)),
                                  std::stof(std::to_string(p.z)));
            if (normalsForAll || i % 2 == 0) {
                f += "vn 0 1 " + std::to_string(i) + "\n";
                normals.push_back(Vec3f(0.f, 1.f, float(i)));
            }
            f += "vt 0.1 0.2\n";
            if (i >= 3 && i % 3 == 0) { // a triangle by negative indices, the last 3 read
                f += "f -1//-1 -3//-3 -2//-2\n";
                triangles.push_back({i, i - 2, i - 1});
            }
            if (i >= 40000 && i % 7 == 0) { // a quad far back, absolute, a/b/c
                const uint32_t a = i - 39000, b = i / 2, c = 5, d = i;
                f += "f " + std::to_string(a + 1) + "/1/1 " + std::to_string(b + 1) + "/2/2\t" +
                     std::to_string(c + 1) + " " + std::to_string(d + 1) + "/3\n";
                triangles.push_back({a, b, c});
                triangles.push_back({a, c, d});
            }
        }
        f += "# the end, without a line end";
        ASSERT_GT(f.size(), size_t(3) << 20);
        // read on all threads, not left to the line-by-line reader (which would hide a wrong
        // result of its own by refusing it)
        TriangleMesh m;
        ASSERT_TRUE(io_internal::readObjInParallel(reinterpret_cast<const uint8_t*>(f.data()),
                                                   f.size(), m));
        EXPECT_TRUE(m.points == points);
        EXPECT_TRUE(m.triangles == triangles);
        if (normalsForAll)
            EXPECT_TRUE(m.normals == normals);
        else
            EXPECT_TRUE(m.normals.empty()) << "normals are kept only one per vertex";

        EXPECT_TRUE(io::readMeshFromMemory(reinterpret_cast<const uint8_t*>(f.data()), f.size(),
                                           io::MeshFormat::Obj, "m.obj")
                        .triangles == triangles);

        // an index past the vertices, far into the file: the message names its line
        const size_t at = f.find("\nf ", f.size() / 2) + 1;
        const size_t line = size_t(std::count(f.begin(), f.begin() + long(at), '\n')) + 1;
        std::string bad = f;
        bad.replace(at, 2, "f 999999 ");
        try {
            io::readMeshFromMemory(reinterpret_cast<const uint8_t*>(bad.data()), bad.size(),
                                   io::MeshFormat::Obj, "m.obj");
            ADD_FAILURE() << "no error";
        } catch (const InputError& e) {
            EXPECT_NE(std::string(e.what()).find("vertex index 999999 outside the"),
                      std::string::npos)
                << e.what();
            EXPECT_NE(std::string(e.what()).find("(at line " + std::to_string(line) + ")"),
                      std::string::npos)
                << e.what();
        }
    }
}

TEST(MeshIO, PolygonsBecomeStripsWithTheirWindingAndArea)
{
    // A convex 1,000-gon (a prism's cap): as a fan its first corner had 999 neighbours, and
    // OpenMesh's decimater spent 34 s on the prism. Read from OBJ (both readers) and PLY, every
    // triangle keeps the polygon's winding, the areas add up to the polygon's, and no corner has
    // more than four neighbours. A quad is still fanned from its first corner.
    const uint32_t n = 1000;
    std::string obj, ply = "ply\nformat ascii 1.0\nelement vertex " + std::to_string(n) +
                           "\nproperty float x\nproperty float y\nproperty float z\n"
                           "element face 1\nproperty list int int vertex_indices\nend_header\n";
    std::string objFace = "f", plyFace = std::to_string(n);
    for (uint32_t i = 0; i < n; ++i) {
        const double a = 2 * M_PI * i / n;
        const std::string v =
            std::to_string(std::cos(a)) + " " + std::to_string(std::sin(a)) + " 0";
        obj += "v " + v + "\n";
        ply += v + "\n";
        objFace += " " + std::to_string(i + 1);
        plyFace += " " + std::to_string(i);
    }
    obj += objFace + "\n";
    ply += plyFace + "\n";
    const auto bytes = [](const std::string& s) {
        return reinterpret_cast<const uint8_t*>(s.data());
    };
    TriangleMesh parallel;
    ASSERT_TRUE(io_internal::readObjInParallel(bytes(obj), obj.size(), parallel));
    const TriangleMesh meshes[] = {
        io::readMeshFromMemory(bytes(obj), obj.size(), io::MeshFormat::Obj, "cap.obj"),
        io::readMeshFromMemory(bytes(ply), ply.size(), io::MeshFormat::Ply, "cap.ply"), parallel};
    const double polygonArea = 0.5 * n * std::sin(2 * M_PI / n);
    for (const TriangleMesh& m : meshes) {
        ASSERT_EQ(m.triangles.size(), n - 2);
        double area = 0;
        size_t clockwise = 0;
        std::vector<std::set<uint32_t>> neighbours(n);
        for (const auto& [a, b, c] : m.triangles) {
            const Vec3f u = m.points[b] - m.points[a], w = m.points[c] - m.points[a];
            const double z = 0.5 * (double(u.x) * w.y - double(u.y) * w.x);
            clockwise += z <= 0;
            area += z;
            neighbours[a].insert({b, c});
            neighbours[b].insert({a, c});
            neighbours[c].insert({a, b});
        }
        EXPECT_EQ(clockwise, 0u);
        EXPECT_NEAR(area, polygonArea, 1e-4 * polygonArea);
        size_t most = 0;
        for (const auto& s : neighbours)
            most = std::max(most, s.size());
        EXPECT_LE(most, 4u);
    }
    const std::string quad = "v 0 0 0\nv 1 0 0\nv 1 1 0\nv 0 1 0\nf 1 2 3 4\n";
    const auto q = io::readMeshFromMemory(bytes(quad), quad.size(), io::MeshFormat::Obj, "q.obj");
    ASSERT_EQ(q.triangles.size(), 2u);
    EXPECT_EQ(q.triangles[0], (std::array<uint32_t, 3>{0, 1, 2}));
    EXPECT_EQ(q.triangles[1], (std::array<uint32_t, 3>{0, 2, 3}));
}
