// MeshIO.cc - OBJ, binary PLY and legacy VTK mesh writers. Each builds the file in memory and
// hands it to writeFileAtomic. OBJ floats are printed in the shortest form that reads back as
// the same float32 (std::to_chars), and OBJ text is encoded in parallel chunks.
#include <fluidsurf/io/MeshIO.h>

#include "io/ByteReader.h"
#include "io/TextParse.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/io/AtomicFile.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <charconv>
#include <vector>

namespace fluidsurf {
namespace io {

using io_internal::lower;

MeshFormat meshFormatFromPath(const std::string& path)
{
    const std::string p = lower(path);
    auto ends = [&](const char* s) {
        const size_t n = std::strlen(s);
        return p.size() >= n && p.compare(p.size() - n, n, s) == 0;
    };
    if (ends(".obj")) return MeshFormat::Obj;
    if (ends(".ply")) return MeshFormat::Ply;
    if (ends(".vtk")) return MeshFormat::Vtk;
    return MeshFormat::Unknown;
}

namespace {

void appendFloat(std::string& s, float v)
{
    char buf[32];
    auto r = std::to_chars(buf, buf + sizeof(buf), v); // shortest text that reads back as v
    s.append(buf, r.ptr);
}

void appendUint(std::string& s, uint64_t v)
{
    char buf[24];
    auto r = std::to_chars(buf, buf + sizeof(buf), v);
    s.append(buf, r.ptr);
}

/// Text lines [0, count) made by line(string&, i), encoded in fixed chunks in parallel and joined
/// in order (the same bytes for any thread count).
template <typename F> void appendLines(std::string& s, size_t count, size_t bytesPerLine, F line)
{
    constexpr size_t kChunk = 8192;
    std::vector<std::string> chunks((count + kChunk - 1) / kChunk);
    tbb::parallel_for(size_t(0), chunks.size(), [&](size_t c) {
        std::string& out = chunks[c];
        out.reserve(kChunk * bytesPerLine);
        for (size_t i = c * kChunk, e = std::min(count, i + kChunk); i < e; ++i)
            line(out, i);
    });
    size_t total = s.size();
    for (const std::string& c : chunks)
        total += c.size();
    s.reserve(total);
    for (const std::string& c : chunks)
        s += c;
}

std::string encodeObj(const TriangleMesh& m)
{
    std::string s = "# fluidsurf mesh: " + std::to_string(m.points.size()) + " vertices, " +
                    std::to_string(m.triangles.size()) + " triangles\n";
    auto vec = [](std::string& out, const char* tag, const Vec3f& v) {
        out += tag;
        appendFloat(out, v.x);
        out += ' ';
        appendFloat(out, v.y);
        out += ' ';
        appendFloat(out, v.z);
        out += '\n';
    };
    appendLines(s, m.points.size(), 40,
                [&](std::string& out, size_t i) { vec(out, "v ", m.points[i]); });
    appendLines(s, m.normals.size(), 40,
                [&](std::string& out, size_t i) { vec(out, "vn ", m.normals[i]); });
    const bool withNormals = !m.normals.empty();
    appendLines(s, m.triangles.size(), 48, [&](std::string& out, size_t i) {
        out += 'f';
        for (uint32_t v : m.triangles[i]) {
            out += ' ';
            appendUint(out, uint64_t(v) + 1);
            if (withNormals) {
                out += "//";
                appendUint(out, uint64_t(v) + 1);
            }
        }
        out += '\n';
    });
    return s;
}

std::string encodePlyMesh(const TriangleMesh& m)
{
    const bool withNormals = !m.normals.empty();
    std::string s = "ply\nformat binary_little_endian 1.0\ncomment written by fluidsurf\n";
    s += "element vertex " + std::to_string(m.points.size()) + "\n";
    s += "property float x\nproperty float y\nproperty float z\n";
    if (withNormals) s += "property float nx\nproperty float ny\nproperty float nz\n";
    s += "element face " + std::to_string(m.triangles.size()) + "\n";
    s += "property list uchar int vertex_indices\nend_header\n";
    const size_t head = s.size();
    const size_t vstride = withNormals ? 24 : 12;
    s.resize(head + m.points.size() * vstride + m.triangles.size() * 13);
    char* p = &s[head];
    for (size_t i = 0; i < m.points.size(); ++i) {
        std::memcpy(p, &m.points[i], 12);
        if (withNormals) std::memcpy(p + 12, &m.normals[i], 12);
        p += vstride;
    }
    for (const auto& t : m.triangles) {
        *p++ = 3;
        for (uint32_t v : t) {
            const int32_t i = int32_t(v);
            std::memcpy(p, &i, 4);
            p += 4;
        }
    }
    return s;
}

void appendBE(std::string& s, const void* v, size_t n)
{
    const char* c = static_cast<const char*>(v);
    for (size_t i = 0; i < n; ++i)
        s += c[n - 1 - i];
}

std::string encodeVtkMesh(const TriangleMesh& m)
{
    std::string s = "# vtk DataFile Version 4.2\nfluidsurf mesh\nBINARY\nDATASET POLYDATA\n";
    s += "POINTS " + std::to_string(m.points.size()) + " float\n";
    s.reserve(s.size() + m.points.size() * 24 + m.triangles.size() * 16 + 256);
    for (const Vec3f& p : m.points)
        appendBE(s, &p.x, 4), appendBE(s, &p.y, 4), appendBE(s, &p.z, 4);
    s += "\nPOLYGONS " + std::to_string(m.triangles.size()) + " " +
         std::to_string(m.triangles.size() * 4) + "\n";
    for (const auto& t : m.triangles) {
        const int32_t three = 3;
        appendBE(s, &three, 4);
        for (uint32_t v : t) {
            const int32_t i = int32_t(v);
            appendBE(s, &i, 4);
        }
    }
    s += "\n";
    if (!m.normals.empty()) {
        s += "POINT_DATA " + std::to_string(m.points.size()) + "\nNORMALS normals float\n";
        for (const Vec3f& n : m.normals)
            appendBE(s, &n.x, 4), appendBE(s, &n.y, 4), appendBE(s, &n.z, 4);
        s += "\n";
    }
    return s;
}

} // namespace

void writeMesh(const TriangleMesh& mesh, const std::string& path)
{
    const MeshFormat format = meshFormatFromPath(path);
    if (format == MeshFormat::Unknown)
        throw OutputError(path + ": unknown mesh file type (writable: .obj .ply .vtk)");
    if (!mesh.normals.empty() && mesh.normals.size() != mesh.points.size())
        throw OutputError(path + ": mesh has " + std::to_string(mesh.normals.size()) +
                          " normals for " + std::to_string(mesh.points.size()) + " vertices");
    if (mesh.points.size() > size_t(INT32_MAX))
        throw OutputError(path + ": mesh has too many vertices for 32-bit indices");
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t)
            if (v >= mesh.points.size())
                throw OutputError(path + ": triangle refers to vertex " + std::to_string(v) +
                                  " of " + std::to_string(mesh.points.size()));
    const std::string bytes = format == MeshFormat::Obj   ? encodeObj(mesh)
                              : format == MeshFormat::Ply ? encodePlyMesh(mesh)
                                                          : encodeVtkMesh(mesh);
    writeFileAtomic(path, bytes.data(), bytes.size());
}

} // namespace io
} // namespace fluidsurf
