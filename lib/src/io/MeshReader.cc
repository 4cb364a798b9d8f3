// MeshReader.cc - reading triangle meshes back (`fluidsurf info`, tests): Wavefront OBJ (v, vn,
// f with any of the a, a/b, a/b/c, a//c forms, negative indices, polygons cut into triangles as
// strips: io/Polygon.h) and PLY (ascii, binary little or big endian; a vertex element with x y z
// [nx ny nz], a face element with a list of indices). Validated like the particle readers: a bad
// file is one InputError naming the file, the problem and where.
#include <fluidsurf/Error.h>
#include <fluidsurf/io/MeshIO.h>

#include "io/ByteReader.h"
#include "io/FileBuffer.h"
#include "io/ObjInParallel.h"
#include "io/PlyHeader.h"
#include "io/Polygon.h"
#include "io/TextParse.h"

#include "util/Memory.h"

#include <cstdio>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

namespace fluidsurf {
namespace io {

using io_internal::ByteReader;

namespace {

TriangleMesh readObj(const uint8_t* data, size_t size, const std::string& path)
{
    ByteReader in(data, size, path);
    TriangleMesh m;
    std::vector<Vec3f> normals;
    size_t lineNo = 0;
    auto fail = [&](const std::string& what) {
        throw InputError(path + ": " + what + " (at line " + std::to_string(lineNo) + ")");
    };
    auto number = [&](const std::string& w) {
        double v;
        if (!io_internal::parseFloat(w.data(), w.data() + w.size(), v))
            fail("'" + w.substr(0, 40) + "' is not a number");
        return float(v);
    };
    std::vector<uint32_t> face;
    while (!in.atEnd()) {
        ++lineNo;
        const std::vector<std::string> w =
            io_internal::splitWords(in.line("an OBJ line", io_internal::kObjLineLimit));
        if (w.empty() || w[0][0] == '#') continue;
        if (w[0] == "v" || w[0] == "vn") {
            if (w.size() < 4) fail("'" + w[0] + "' needs three numbers");
            (w[0] == "v" ? m.points : normals)
                .push_back(Vec3f(number(w[1]), number(w[2]), number(w[3])));
        } else if (w[0] == "f") {
            if (w.size() < 4) fail("a face needs at least three vertices");
            face.clear();
            for (size_t k = 1; k < w.size(); ++k) {
                const std::string index = w[k].substr(0, w[k].find('/'));
                int64_t i;
                if (!io_internal::parseInt(index.data(), index.data() + index.size(), i) || i == 0)
                    fail("bad vertex index '" + w[k].substr(0, 40) + "'");
                const int64_t n = int64_t(m.points.size());
                if (i < 0) i += n + 1; // relative to the vertices read so far
                if (i < 1 || i > n)
                    fail("vertex index " + index + " outside the " + std::to_string(n) +
                         " vertices read so far");
                face.push_back(uint32_t(i - 1));
            }
            io_internal::triangulatePolygon(face.data(), face.size(),
                                            [&](uint32_t a, uint32_t b, uint32_t c) {
                                                m.triangles.push_back({a, b, c});
                                            });
        }
        // Other statements (vt, o, g, s, usemtl, mtllib, l, p) carry nothing checkMesh needs.
    }
    // Normals are kept when there is one per vertex (as fluidsurf writes them: f v//v).
    if (normals.size() == m.points.size()) m.normals = std::move(normals);
    return m;
}

/// item(p, i) for each of count items of `stride` bytes from p, on all threads.
template <typename F> void forEachItem(const uint8_t* p, size_t count, size_t stride, F&& item)
{
    tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1 << 14),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i)
                              item(p + i * stride, i);
                      });
}

/// A binary vertex element without lists, read where it lies, on all threads (value by value on
/// one thread, the 1.7M-particle frame's 48 MB raw mesh took 0.15-0.2 s of `post` on 2 cores).
/// False, having read nothing, for any other: readPly reads it item by item.
bool readVertices(ByteReader& in, const io_internal::PlyElement& e, size_t count, bool be,
                  const int (&xyz)[3], const int* nxyz, TriangleMesh& m)
{
    std::vector<size_t> offset(e.props.size() + 1, 0);
    for (size_t k = 0; k < e.props.size(); ++k) {
        if (e.props[k].isList) return false;
        offset[k + 1] = offset[k] + e.props[k].type.size;
    }
    const size_t stride = offset.back();
    if (stride == 0 || count > in.remaining() / stride) return false;
    const uint8_t* p = in.take(count * stride, "PLY data");
    const size_t first = m.points.size(), firstNormal = m.normals.size();
    util::resizeInParallel(m.points, first + count);
    if (nxyz) util::resizeInParallel(m.normals, firstNormal + count);
    forEachItem(p, count, stride, [&](const uint8_t* item, size_t i) {
        auto value = [&](int k) {
            return float(
                io_internal::loadPlyNumber(item + offset[size_t(k)], e.props[size_t(k)].type, be));
        };
        m.points[first + i] = Vec3f(value(xyz[0]), value(xyz[1]), value(xyz[2]));
        if (nxyz)
            m.normals[firstNormal + i] = Vec3f(value(nxyz[0]), value(nxyz[1]), value(nxyz[2]));
    });
    return true;
}

/// A binary face element that holds only its index list, each face a triangle of points read
/// so far, on all threads: whether that is so is checked first, at the places it implies
/// (each list 3 long puts the next where the check looks). False, having read nothing,
/// otherwise: readPly reads it item by item, and names what is wrong.
bool readTriangles(ByteReader& in, const io_internal::PlyElement& e, size_t count, bool be,
                   TriangleMesh& m)
{
    if (e.props.size() != 1) return false;
    const io_internal::PlyProperty& list = e.props[0]; // (the index list: the caller's check)
    const size_t lengthSize = list.countType.size, stride = lengthSize + 3 * list.type.size;
    if (count > in.remaining() / stride) return false;
    const uint8_t* p = in.cursor();
    const double points = double(m.points.size());
    auto index = [&](const uint8_t* item, int c) {
        return io_internal::loadPlyNumber(item + lengthSize + size_t(c) * list.type.size, list.type,
                                          be);
    };
    const bool triangles = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, count, 1 << 14), true,
        [&](const tbb::blocked_range<size_t>& r, bool ok) {
            for (size_t i = r.begin(); i != r.end() && ok; ++i) {
                const uint8_t* item = p + i * stride;
                ok = io_internal::loadPlyNumber(item, list.countType, be) == 3;
                for (int c = 0; c < 3 && ok; ++c) {
                    const double v = index(item, c);
                    ok = v >= 0 && v < points;
                }
            }
            return ok;
        },
        [](bool a, bool b) { return a && b; });
    if (!triangles) return false;
    in.take(count * stride, "PLY data");
    const size_t first = m.triangles.size();
    util::resizeInParallel(m.triangles, first + count);
    forEachItem(p, count, stride, [&](const uint8_t* item, size_t i) {
        m.triangles[first + i] = {uint32_t(index(item, 0)), uint32_t(index(item, 1)),
                                  uint32_t(index(item, 2))};
    });
    return true;
}

TriangleMesh readPly(const uint8_t* data, size_t size, const std::string& path,
                     std::vector<std::string>* dropped)
{
    ByteReader in(data, size, path);
    const io_internal::PlyHeader header = io_internal::readPlyHeader(in);
    const io_internal::PlyFormat format = header.format;
    TriangleMesh m;
    for (const io_internal::PlyElement& e : header.elements) {
        // Every item takes at least one byte (binary) or two characters (ascii): a count beyond
        // that cannot be true and must not size an allocation.
        size_t minBytes = 0;
        for (const io_internal::PlyProperty& p : e.props)
            minBytes += format == io_internal::PlyFormat::Ascii
                            ? 2
                            : (p.isList ? p.countType : p.type).size;
        const size_t count = in.checkedCount(e.count, std::max<size_t>(minBytes, 1),
                                             ("PLY " + e.name + " items").c_str());
        const bool vertex = e.name == "vertex", faceElement = e.name == "face";
        int xyz[3] = {-1, -1, -1}, nxyz[3] = {-1, -1, -1}, indices = -1;
        for (size_t k = 0; k < e.props.size(); ++k) {
            const std::string& n = e.props[k].name;
            for (int a = 0; a < 3; ++a) {
                if (n == std::string(1, "xyz"[a])) xyz[a] = int(k);
                if (n == std::string("n") + "xyz"[a]) nxyz[a] = int(k);
            }
            if (e.props[k].isList && (n == "vertex_indices" || n == "vertex_index"))
                indices = int(k);
            const bool kept = n.size() == 1
                                  ? n.find_first_of("xyz") == 0
                                  : n.size() == 2 && n[0] == 'n' && n.find_first_of("xyz", 1) == 1;
            if (vertex && dropped && !kept) dropped->push_back(n);
        }
        if (vertex && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0))
            in.fail("the PLY vertex element has no x, y, z properties");
        if (faceElement && indices < 0) in.fail("the PLY face element has no vertex_indices list");
        const bool withNormals = vertex && nxyz[0] >= 0 && nxyz[1] >= 0 && nxyz[2] >= 0;
        const bool be = format == io_internal::PlyFormat::BigEndian;
        if (format != io_internal::PlyFormat::Ascii &&
            (vertex ? readVertices(in, e, count, be, xyz, withNormals ? nxyz : nullptr, m)
                    : faceElement && indices == 0 && readTriangles(in, e, count, be, m)))
            continue;
        if (vertex) m.points.reserve(count);
        if (withNormals) m.normals.reserve(count);
        std::vector<double> values(e.props.size());
        std::vector<uint32_t> face;
        for (size_t item = 0; item < count; ++item) {
            for (size_t k = 0; k < e.props.size(); ++k) {
                const io_internal::PlyProperty& p = e.props[k];
                if (!p.isList) {
                    values[k] = io_internal::readPlyValue(in, p.type, format, "PLY data");
                    continue;
                }
                const double length =
                    io_internal::readPlyValue(in, p.countType, format, "PLY data");
                if (!(length >= 0 && length <= 1 << 16)) in.fail("bad PLY list length");
                face.clear();
                for (int v = 0; v < int(length); ++v) {
                    const double index = io_internal::readPlyValue(in, p.type, format, "PLY data");
                    if (int(k) == indices) {
                        if (!(index >= 0 && index < double(m.points.size())))
                            in.fail("face vertex index " + std::to_string(int64_t(index)) +
                                    " outside the " + std::to_string(m.points.size()) +
                                    " vertices");
                        face.push_back(uint32_t(index));
                    }
                }
                if (int(k) == indices) {
                    if (face.size() < 3) in.fail("a PLY face with fewer than three vertices");
                    io_internal::triangulatePolygon(face.data(), face.size(),
                                                    [&](uint32_t a, uint32_t b, uint32_t c) {
                                                        m.triangles.push_back({a, b, c});
                                                    });
                }
            }
            if (vertex) {
                m.points.push_back(
                    Vec3f(float(values[xyz[0]]), float(values[xyz[1]]), float(values[xyz[2]])));
                if (withNormals)
                    m.normals.push_back(Vec3f(float(values[nxyz[0]]), float(values[nxyz[1]]),
                                              float(values[nxyz[2]])));
            }
        }
    }
    return m;
}

/// InputError at the first vertex that is not finite or lies past kMaxCoordinate: one NaN turned
/// every vertex of `post`'s output into NaN (its quadrics and normals sum over neighbours), one
/// at 1e38 pulled most of them to the origin.
TriangleMesh requireFiniteVertices(TriangleMesh m, const std::string& source)
{
    for (size_t i = 0; i < m.points.size(); ++i)
        if (!m.points[i].isWithinRange()) {
            char text[200];
            std::snprintf(text, sizeof(text),
                          ": vertex %zu of %zu is at (%g, %g, %g); coordinates must be finite and "
                          "within +-%g",
                          i + 1, m.points.size(), double(m.points[i].x), double(m.points[i].y),
                          double(m.points[i].z), kMaxCoordinate);
            throw InputError(source + text);
        }
    return m;
}

} // namespace

TriangleMesh readMeshFromMemory(const uint8_t* data, size_t size, MeshFormat format,
                                const std::string& source, std::vector<std::string>* dropped)
{
    if (format != MeshFormat::Obj && format != MeshFormat::Ply)
        throw InputError(source + ": cannot read this mesh type (readable: .obj .ply; .vtk "
                                  "meshes are written only)");
    if (size == 0) throw InputError(source + ": file is empty");
    if (format == MeshFormat::Ply)
        return requireFiniteVertices(readPly(data, size, source, dropped), source);
    TriangleMesh m;
    if (io_internal::readObjInParallel(data, size, m))
        return requireFiniteVertices(std::move(m), source);
    return requireFiniteVertices(readObj(data, size, source), source);
}

TriangleMesh readMesh(const std::string& path, std::vector<std::string>* dropped)
{
    const std::vector<uint8_t> bytes = io_internal::readFile(path);
    return readMeshFromMemory(bytes.data(), bytes.size(), meshFormatFromPath(path), path, dropped);
}

} // namespace io
} // namespace fluidsurf
