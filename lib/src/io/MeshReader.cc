// MeshReader.cc - reading triangle meshes back (`fluidsurf info`, tests): Wavefront OBJ (v, vn,
// f with any of the a, a/b, a/b/c, a//c forms, negative indices, polygons fanned into triangles)
// and PLY (ascii, binary little or big endian; a vertex element with x y z [nx ny nz], a face
// element with a list of indices). Validated like the particle readers: a bad file is one
// InputError naming the file, the problem and where.
#include <fluidsurf/Error.h>
#include <fluidsurf/io/MeshIO.h>

#include "io/ByteReader.h"
#include "io/FileBuffer.h"
#include "io/TextParse.h"

namespace fluidsurf {
namespace io {

using io_internal::ByteReader;

namespace {

TriangleMesh readObj(const std::vector<uint8_t>& bytes, const std::string& path)
{
    ByteReader in(bytes.data(), bytes.size(), path);
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
        const std::vector<std::string> w = io_internal::splitWords(in.line("an OBJ line", 1 << 20));
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
            for (size_t k = 1; k + 1 < face.size(); ++k)
                m.triangles.push_back({face[0], face[k], face[k + 1]});
        }
        // Other statements (vt, o, g, s, usemtl, mtllib, l, p) carry nothing checkMesh needs.
    }
    // Normals are kept when there is one per vertex (as fluidsurf writes them: f v//v).
    if (normals.size() == m.points.size()) m.normals = std::move(normals);
    return m;
}

enum class PlyType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Float32, Float64 };

PlyType plyType(const ByteReader& in, const std::string& name)
{
    static const std::pair<const char*, PlyType> names[] = {
        {"char", PlyType::Int8},      {"int8", PlyType::Int8},       {"uchar", PlyType::UInt8},
        {"uint8", PlyType::UInt8},    {"short", PlyType::Int16},     {"int16", PlyType::Int16},
        {"ushort", PlyType::UInt16},  {"uint16", PlyType::UInt16},   {"int", PlyType::Int32},
        {"int32", PlyType::Int32},    {"uint", PlyType::UInt32},     {"uint32", PlyType::UInt32},
        {"float", PlyType::Float32},  {"float32", PlyType::Float32}, {"double", PlyType::Float64},
        {"float64", PlyType::Float64}};
    for (const auto& n : names)
        if (name == n.first) return n.second;
    in.fail("unknown PLY property type '" + name.substr(0, 40) + "'");
}

size_t plySize(PlyType t)
{
    switch (t) {
    case PlyType::Int8:
    case PlyType::UInt8:
        return 1;
    case PlyType::Int16:
    case PlyType::UInt16:
        return 2;
    case PlyType::Float64:
        return 8;
    default:
        return 4;
    }
}

struct PlyProperty
{
    std::string name;
    PlyType type = PlyType::Float32;
    bool list = false;
    PlyType countType = PlyType::UInt8;
};

struct PlyElement
{
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> properties;
};

/// One value of a PLY body, ascii or binary.
double plyValue(ByteReader& in, PlyType t, int format)
{
    if (format == 0) return io_internal::readAsciiNumber(in, "PLY data");
    const bool big = format == 2;
    switch (t) {
    case PlyType::Int8:
        return in.read<int8_t>(big, "PLY data");
    case PlyType::UInt8:
        return in.read<uint8_t>(big, "PLY data");
    case PlyType::Int16:
        return in.read<int16_t>(big, "PLY data");
    case PlyType::UInt16:
        return in.read<uint16_t>(big, "PLY data");
    case PlyType::Int32:
        return in.read<int32_t>(big, "PLY data");
    case PlyType::UInt32:
        return in.read<uint32_t>(big, "PLY data");
    case PlyType::Float32:
        return in.read<float>(big, "PLY data");
    case PlyType::Float64:
        return in.read<double>(big, "PLY data");
    }
    return 0;
}

TriangleMesh readPly(const std::vector<uint8_t>& bytes, const std::string& path)
{
    ByteReader in(bytes.data(), bytes.size(), path);
    if (in.line("the PLY magic") != "ply") in.failAt(0, "not a PLY file (missing 'ply' magic)");
    int format = -1; // 0 ascii, 1 little endian, 2 big endian
    std::vector<PlyElement> elements;
    for (;;) {
        const std::vector<std::string> w = io_internal::splitWords(in.line("the PLY header"));
        if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
        if (w[0] == "end_header") break;
        if (w[0] == "format" && w.size() >= 2) {
            format = w[1] == "ascii"                  ? 0
                     : w[1] == "binary_little_endian" ? 1
                     : w[1] == "binary_big_endian"    ? 2
                                                      : -1;
            if (format < 0) in.fail("unknown PLY format '" + w[1].substr(0, 40) + "'");
        } else if (w[0] == "element" && w.size() >= 3) {
            elements.push_back({w[1], io_internal::parseCount(in, w[2], "element count"), {}});
        } else if (w[0] == "property" && !elements.empty()) {
            PlyProperty p;
            if (w.size() >= 5 && w[1] == "list") {
                p.list = true, p.countType = plyType(in, w[2]), p.type = plyType(in, w[3]);
                p.name = w[4];
            } else if (w.size() >= 3) {
                p.type = plyType(in, w[1]), p.name = w[2];
            } else {
                in.fail("malformed PLY property line");
            }
            elements.back().properties.push_back(p);
        } else {
            in.fail("unexpected PLY header line '" + w[0].substr(0, 40) + "'");
        }
    }
    if (format < 0) in.fail("PLY header without a format line");
    TriangleMesh m;
    for (const PlyElement& e : elements) {
        // Every item takes at least one byte (binary) or two characters (ascii): a count beyond
        // that cannot be true and must not size an allocation.
        size_t minBytes = 0;
        for (const PlyProperty& p : e.properties)
            minBytes += format == 0 ? 2 : plySize(p.list ? p.countType : p.type);
        const size_t count = in.checkedCount(e.count, std::max<size_t>(minBytes, 1),
                                             ("PLY " + e.name + " items").c_str());
        const bool vertex = e.name == "vertex", faceElement = e.name == "face";
        int xyz[3] = {-1, -1, -1}, nxyz[3] = {-1, -1, -1}, indices = -1;
        for (size_t k = 0; k < e.properties.size(); ++k) {
            const std::string& n = e.properties[k].name;
            for (int a = 0; a < 3; ++a) {
                if (n == std::string(1, "xyz"[a])) xyz[a] = int(k);
                if (n == std::string("n") + "xyz"[a]) nxyz[a] = int(k);
            }
            if (e.properties[k].list && (n == "vertex_indices" || n == "vertex_index"))
                indices = int(k);
        }
        if (vertex && (xyz[0] < 0 || xyz[1] < 0 || xyz[2] < 0))
            in.fail("the PLY vertex element has no x, y, z properties");
        if (faceElement && indices < 0) in.fail("the PLY face element has no vertex_indices list");
        const bool withNormals = vertex && nxyz[0] >= 0 && nxyz[1] >= 0 && nxyz[2] >= 0;
        if (vertex) m.points.reserve(count);
        if (withNormals) m.normals.reserve(count);
        std::vector<double> values(e.properties.size());
        std::vector<uint32_t> face;
        for (size_t item = 0; item < count; ++item) {
            for (size_t k = 0; k < e.properties.size(); ++k) {
                const PlyProperty& p = e.properties[k];
                if (!p.list) {
                    values[k] = plyValue(in, p.type, format);
                    continue;
                }
                const double length = plyValue(in, p.countType, format);
                if (!(length >= 0 && length <= 1 << 16)) in.fail("bad PLY list length");
                face.clear();
                for (int v = 0; v < int(length); ++v) {
                    const double index = plyValue(in, p.type, format);
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
                    for (size_t f = 1; f + 1 < face.size(); ++f)
                        m.triangles.push_back({face[0], face[f], face[f + 1]});
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

} // namespace

TriangleMesh readMesh(const std::string& path)
{
    const std::vector<uint8_t> bytes = io_internal::readFile(path);
    switch (meshFormatFromPath(path)) {
    case MeshFormat::Obj:
        return readObj(bytes, path);
    case MeshFormat::Ply:
        return readPly(bytes, path);
    default:
        throw InputError(path + ": cannot read this mesh type (readable: .obj .ply; .vtk meshes "
                                "are written only)");
    }
}

} // namespace io
} // namespace fluidsurf
