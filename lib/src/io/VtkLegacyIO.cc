// VtkLegacyIO.cc - legacy VTK (.vtk) point sets: ASCII and BINARY (big-endian),
// DATASET POLYDATA / UNSTRUCTURED_GRID, float or double POINTS, POINT_DATA SCALARS / VECTORS /
// NORMALS / TEXTURE_COORDINATES / TENSORS / FIELD arrays. Cells (VTK 4.x and 5.x layouts) and
// CELL_DATA are read past, since particles are the points. The writer emits BINARY POLYDATA
// with one VERTICES cell per particle (so ParaView draws them) and a FIELD array per attribute.
// A binary file is read from where its sections lie (FileCursor), with no copy of the whole file:
// the 13.1M drop's 262 MB file is 157 MB of points and 105 MB of cells, which are skipped.
#include "io/BigEndian.h"
#include "io/FileCursor.h"
#include "io/StreamFile.h"
#include "io/TextParse.h"

#include "util/Memory.h"

#include <fluidsurf/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <optional>
#include <type_traits>

namespace fluidsurf {
namespace io_internal {

namespace {

enum class VtkType { Int8, UInt8, Int16, UInt16, Int32, UInt32, Int64, UInt64, Float32, Float64 };

bool vtkTypeFromName(const std::string& name, VtkType& t)
{
    const std::string n = lower(name);
    if (n == "char")
        t = VtkType::Int8;
    else if (n == "unsigned_char")
        t = VtkType::UInt8;
    else if (n == "short")
        t = VtkType::Int16;
    else if (n == "unsigned_short")
        t = VtkType::UInt16;
    else if (n == "int" || n == "vtkidtype")
        t = VtkType::Int32;
    else if (n == "unsigned_int")
        t = VtkType::UInt32;
    else if (n == "long" || n == "vtktypeint64")
        t = VtkType::Int64;
    else if (n == "unsigned_long" || n == "vtktypeuint64")
        t = VtkType::UInt64;
    else if (n == "float")
        t = VtkType::Float32;
    else if (n == "double")
        t = VtkType::Float64;
    else
        return false;
    return true;
}

size_t vtkTypeSize(VtkType t)
{
    switch (t) {
    case VtkType::Int8:
    case VtkType::UInt8:
        return 1;
    case VtkType::Int16:
    case VtkType::UInt16:
        return 2;
    case VtkType::Int32:
    case VtkType::UInt32:
    case VtkType::Float32:
        return 4;
    default:
        return 8;
    }
}

bool isFloatType(VtkType t)
{
    return t == VtkType::Float32 || t == VtkType::Float64;
}

/// In: a ByteReader over the file in memory, or a FileCursor over the file itself (binary
/// files only: ASCII values are parsed from memory).
template <typename In> class VtkLegacyParser
{
public:
    explicit VtkLegacyParser(In input) : in(std::move(input)) {}

    ParticleSet parse(std::string* detail)
    {
        readHeader(detail);
        return readBody();
    }

    /// The lines up to DATASET; whether the values are binary.
    bool readHeader(std::string* detail)
    {
        const std::string magic = in.line("the header", 256);
        if (magic.rfind("# vtk DataFile Version", 0) != 0)
            in.failAt(
                0, "not a legacy VTK file (first line must start with '# vtk DataFile Version')");
        in.line("the title line", 1 << 16);
        const std::string mode = lower(nextLine("the ASCII/BINARY line")[0]);
        if (mode == "ascii")
            mBinary = false;
        else if (mode == "binary")
            mBinary = true;
        else
            fail("expected ASCII or BINARY, found '" + mode.substr(0, 40) + "'");

        auto words = nextLine("DATASET");
        if (words.size() < 2 || lower(words[0]) != "dataset") fail("expected DATASET");
        const std::string dataset = lower(words[1]);
        if (dataset != "polydata" && dataset != "unstructured_grid")
            fail("DATASET " + words[1] +
                 " is not a point set (POLYDATA or UNSTRUCTURED_GRID expected)");
        if (detail) *detail = std::string(mBinary ? "BINARY " : "ASCII ") + words[1];
        return mBinary;
    }

    /// The sections after DATASET: the points and their arrays.
    ParticleSet readBody()
    {
        bool havePoints = false;
        enum { None, Points, Cells } scope = None;
        uint64_t cellCount = 0, unstructuredCells = 0; // CELLS waiting for their CELL_TYPES
        std::vector<std::string> w;
        while (nextLineOrEnd(w)) {
            const std::string key = lower(w[0]);
            if (key == "points") {
                if (havePoints) fail("second POINTS section");
                readPoints(w);
                havePoints = true;
            } else if (key == "vertices" || key == "lines" || key == "polygons" ||
                       key == "triangle_strips" || key == "cells") {
                skipCells(w);
                if (key == "cells") unstructuredCells = parseCount(in, w[1], "cell count");
            } else if (key == "cell_types") {
                need(w, 2);
                const uint64_t types = parseCount(in, w[1], "CELL_TYPES count");
                if (types != unstructuredCells)
                    fail("CELL_TYPES " + w[1] + " does not match CELLS " +
                         std::to_string(unstructuredCells));
                skipValues(types, VtkType::Int32, "CELL_TYPES");
                unstructuredCells = 0;
            } else if (key == "point_data") {
                need(w, 2);
                if (!havePoints) fail("POINT_DATA before POINTS");
                if (parseCount(in, w[1], "POINT_DATA count") != mSet.size())
                    fail("POINT_DATA " + w[1] + " does not match POINTS " +
                         std::to_string(mSet.size()));
                scope = Points;
            } else if (key == "cell_data") {
                need(w, 2);
                cellCount = parseCount(in, w[1], "CELL_DATA count");
                scope = Cells;
            } else if (key == "metadata") {
                skipMetadata();
            } else if (scope != None && isAttributeKeyword(key)) {
                readAttribute(w, scope == Points ? mSet.size() : cellCount, scope == Points);
            } else {
                fail("unexpected keyword '" + w[0].substr(0, 40) + "'");
            }
        }
        if (!havePoints) fail("no POINTS section");
        // An unstructured grid's cells need their types: a file that ends between the two was
        // cut, and whatever followed (point data) is lost.
        if (unstructuredCells)
            fail("CELLS without CELL_TYPES: the file ends early (truncated?), point data lost");
        return std::move(mSet);
    }

private:
    static constexpr bool kInMemory = std::is_same_v<In, ByteReader>;
    In in;
    bool mBinary = false;
    ParticleSet mSet;

    [[noreturn]] void fail(const std::string& what) { in.fail(what); }
    void need(const std::vector<std::string>& w, size_t n)
    {
        if (w.size() < n) fail("incomplete '" + w[0] + "' line");
    }

    bool nextLineOrEnd(std::vector<std::string>& words)
    {
        while (!in.atEnd()) {
            words = splitWords(in.line("a section header"));
            if (!words.empty()) return true;
        }
        return false;
    }
    std::vector<std::string> nextLine(const char* what)
    {
        std::vector<std::string> w;
        if (!nextLineOrEnd(w)) fail(std::string("file ends before ") + what);
        return w;
    }

    static bool isAttributeKeyword(const std::string& k)
    {
        return k == "scalars" || k == "vectors" || k == "normals" || k == "texture_coordinates" ||
               k == "tensors" || k == "field" || k == "color_scalars" || k == "lookup_table";
    }

    VtkType typeOf(const std::string& name)
    {
        VtkType t;
        if (!vtkTypeFromName(name, t)) fail("unsupported data type '" + name.substr(0, 40) + "'");
        return t;
    }

    /// Read count values of type t as doubles (floats) or int64 (integers) into out.
    template <typename Out>
    void readValues(uint64_t count, VtkType t, const char* what, std::vector<Out>& out)
    {
        if (mBinary) {
            const size_t n = in.checkedCount(count, vtkTypeSize(t), what);
            util::resizeInParallel(out, n);
            records(in, n, vtkTypeSize(t), what, [&](size_t first, size_t k, const uint8_t* p) {
                convertBinary(p, k, t, out.data() + first);
            });
        } else if constexpr (!kInMemory) {
            fail("ASCII values are parsed from memory"); // readVtkLegacy(file) hands them over
        } else {
            const size_t n = in.checkedCount(count, 1, what); // >= 1 byte per ASCII value
            out.resize(n);
            for (size_t i = 0; i < n; ++i) {
                const double v = readAsciiNumber(in, what);
                if constexpr (std::is_integral_v<Out>) {
                    if (!isFloatType(t) && (v != std::floor(v) || std::fabs(v) > 9.2e18))
                        fail(std::string("non-integer value in integer array ") + what);
                }
                out[i] = Out(v);
            }
        }
    }

    template <typename Out>
    static void convertBinary(const uint8_t* p, size_t n, VtkType t, Out* out)
    {
        const size_t s = vtkTypeSize(t);
        for (size_t i = 0; i < n; ++i, p += s) {
            switch (t) {
            case VtkType::Int8:
                out[i] = Out(int8_t(*p));
                break;
            case VtkType::UInt8:
                out[i] = Out(*p);
                break;
            case VtkType::Int16:
                out[i] = Out(loadAs<int16_t>(p, true));
                break;
            case VtkType::UInt16:
                out[i] = Out(loadAs<uint16_t>(p, true));
                break;
            case VtkType::Int32:
                out[i] = Out(loadAs<int32_t>(p, true));
                break;
            case VtkType::UInt32:
                out[i] = Out(loadAs<uint32_t>(p, true));
                break;
            case VtkType::Int64:
                out[i] = Out(loadAs<int64_t>(p, true));
                break;
            case VtkType::UInt64:
                out[i] = Out(loadAs<uint64_t>(p, true));
                break;
            case VtkType::Float32:
                out[i] = Out(loadAs<float>(p, true));
                break;
            case VtkType::Float64:
                out[i] = Out(loadAs<double>(p, true));
                break;
            }
        }
    }

    void skipValues(uint64_t count, VtkType t, const char* what)
    {
        if (mBinary) {
            in.skip(in.checkedCount(count, vtkTypeSize(t), what) * vtkTypeSize(t), what);
        } else if constexpr (!kInMemory) {
            fail("ASCII values are parsed from memory");
        } else {
            const size_t n = in.checkedCount(count, 1, what);
            for (size_t i = 0; i < n; ++i)
                readAsciiNumber(in, what);
        }
    }

    void readPoints(const std::vector<std::string>& w)
    {
        need(w, 3);
        const uint64_t n = parseCount(in, w[1], "POINTS count");
        const VtkType t = typeOf(w[2]);
        const uint64_t values = mulChecked(in, n, 3, "POINTS");
        if (mBinary && t == VtkType::Float32) {
            // Fast path for the common case: big-endian float32 straight into positions, on all
            // threads.
            const size_t count = in.checkedCount(n, 12, "points");
            util::resizeInParallel(mSet.positions, count);
            records(in, count, 12, "points", [&](size_t first, size_t k, const uint8_t* q) {
                for (size_t i = first; i != first + k; ++i, q += 12)
                    mSet.positions[i] = Vec3f(loadAs<float>(q, true), loadAs<float>(q + 4, true),
                                              loadAs<float>(q + 8, true));
            });
        } else {
            std::vector<double> v;
            readValues(values, t, "points", v);
            mSet.positions.resize(size_t(n));
            for (size_t i = 0; i < size_t(n); ++i)
                mSet.positions[i] =
                    Vec3f(float(v[3 * i]), float(v[3 * i + 1]), float(v[3 * i + 2]));
        }
        skipMetadataIfPresent();
    }

    void skipCells(const std::vector<std::string>& w)
    {
        need(w, 3);
        const uint64_t n = parseCount(in, w[1], "cell count");
        const uint64_t size = parseCount(in, w[2], "cell list size");
        // VTK 5.x writes "OFFSETS type" and "CONNECTIVITY type" arrays; 4.x one int list.
        const size_t mark = in.offset();
        std::vector<std::string> next;
        if (nextLineOrEnd(next) && lower(next[0]) == "offsets") {
            need(next, 2);
            skipValues(n, typeOf(next[1]), "cell offsets");
            auto conn = nextLine("CONNECTIVITY");
            if (lower(conn[0]) != "connectivity" || conn.size() < 2) fail("expected CONNECTIVITY");
            skipValues(size, typeOf(conn[1]), "cell connectivity");
        } else {
            in.seek(mark);
            skipValues(size, VtkType::Int32, "cells");
        }
        skipMetadataIfPresent();
    }

    void skipMetadata()
    {
        // METADATA blocks end at the first empty line.
        while (!in.atEnd()) {
            const std::string l = in.line("METADATA", 1 << 20);
            if (splitWords(l).empty()) return;
        }
    }
    void skipMetadataIfPresent()
    {
        const size_t mark = in.offset();
        std::vector<std::string> w;
        if (nextLineOrEnd(w) && lower(w[0]) == "metadata")
            skipMetadata();
        else
            in.seek(mark);
    }

    void storeArray(const std::string& name, int comps, VtkType t, uint64_t tuples, bool keep,
                    const char* what)
    {
        const uint64_t count = mulChecked(in, tuples, uint64_t(comps), what);
        if (!keep) {
            skipValues(count, t, what);
        } else if (isFloatType(t)) {
            std::vector<float> v; // float(value), as through a double before
            readValues(count, t, what, v);
            mSet.addFloat(name, comps, std::move(v));
        } else {
            std::vector<int64_t> v;
            readValues(count, t, what, v);
            mSet.addInt(name, comps, std::move(v));
        }
        skipMetadataIfPresent();
    }

    void readAttribute(const std::vector<std::string>& w, uint64_t tuples, bool keep)
    {
        const std::string key = lower(w[0]);
        if (key == "scalars") {
            need(w, 3);
            const uint64_t comps = w.size() >= 4 ? parseCount(in, w[3], "component count") : 1;
            if (comps < 1 || comps > 16) fail("SCALARS with " + w[3] + " components");
            // LOOKUP_TABLE line follows (optional in some writers).
            const size_t mark = in.offset();
            std::vector<std::string> lt;
            if (!(nextLineOrEnd(lt) && lower(lt[0]) == "lookup_table")) in.seek(mark);
            storeArray(w[1], int(comps), typeOf(w[2]), tuples, keep, "SCALARS data");
        } else if (key == "vectors" || key == "normals") {
            need(w, 3);
            storeArray(w[1], 3, typeOf(w[2]), tuples, keep, "VECTORS data");
        } else if (key == "texture_coordinates") {
            need(w, 4);
            const uint64_t dim = parseCount(in, w[2], "texture dimension");
            if (dim < 1 || dim > 3) fail("bad TEXTURE_COORDINATES dimension");
            storeArray(w[1], int(dim), typeOf(w[3]), tuples, keep, "TEXTURE_COORDINATES data");
        } else if (key == "tensors") {
            need(w, 3);
            storeArray(w[1], 9, typeOf(w[2]), tuples, keep, "TENSORS data");
        } else if (key == "color_scalars") {
            need(w, 3);
            const uint64_t comps = parseCount(in, w[2], "color components");
            if (comps < 1 || comps > 16) fail("bad COLOR_SCALARS component count");
            storeArray(w[1], int(comps), mBinary ? VtkType::UInt8 : VtkType::Float32, tuples, false,
                       "COLOR_SCALARS data");
        } else if (key == "lookup_table") {
            need(w, 3);
            const uint64_t n = parseCount(in, w[2], "LOOKUP_TABLE size");
            skipValues(mulChecked(in, n, 4, "LOOKUP_TABLE"),
                       mBinary ? VtkType::UInt8 : VtkType::Float32, "LOOKUP_TABLE data");
        } else if (key == "field") {
            need(w, 3);
            const uint64_t arrays = parseCount(in, w[2], "FIELD array count");
            for (uint64_t a = 0; a < arrays; ++a) {
                auto f = nextLine("FIELD array header");
                if (lower(f[0]) == "metadata") {
                    skipMetadata();
                    --a;
                    continue;
                }
                if (f.size() < 4) fail("incomplete FIELD array header");
                const uint64_t comps = parseCount(in, f[1], "FIELD components");
                const uint64_t n = parseCount(in, f[2], "FIELD tuples");
                if (comps < 1 || comps > 16)
                    fail("FIELD array '" + f[0] + "' has " + f[1] + " components");
                if (keep && n != tuples)
                    fail("FIELD array '" + f[0] + "' has " + f[2] + " tuples for " +
                         std::to_string(tuples) + " points");
                storeArray(f[0], int(comps), typeOf(f[3]), n, keep, "FIELD data");
            }
        }
    }
};

} // namespace

ParticleSet readVtkLegacy(const uint8_t* data, size_t size, const std::string& src,
                          std::string* detail)
{
    return VtkLegacyParser<ByteReader>(ByteReader(data, size, src)).parse(detail);
}

std::optional<ParticleSet> readVtkLegacy(const OpenFile& file, const std::string& src,
                                         std::string* detail)
{
    VtkLegacyParser<FileCursor> parser{FileCursor(file, src)};
    if (!parser.readHeader(detail)) return std::nullopt;
    return parser.readBody();
}

void writeVtkLegacy(const ParticleSet& ps, io::StreamFile& out)
{
    ps.validate();
    if (ps.size() > size_t(INT32_MAX / 2))
        throw OutputError("too many particles for legacy VTK's int32 cells");
    for (const Attribute& a : ps.attributes)
        if (a.name.empty() || a.name.find_first_of(" \t\r\n") != std::string::npos)
            throw OutputError("attribute name '" + a.name + "' cannot be stored in legacy VTK");
    const std::string n = std::to_string(ps.size());
    out.write("# vtk DataFile Version 4.2\nfluidsurf particles\nBINARY\nDATASET POLYDATA\nPOINTS " +
              n + " float\n");
    io::writeItems(out, ps.size(), 12, [&](std::string& o, size_t i) {
        const Vec3f& p = ps.positions[i];
        const uint32_t b[3] = {bitsOf(p.x), bitsOf(p.y), bitsOf(p.z)};
        appendBigEndian(o, b, 3);
    });
    out.write("\nVERTICES " + n + " " + std::to_string(2 * ps.size()) + "\n");
    io::writeItems(out, ps.size(), 8, [&](std::string& o, size_t i) {
        const uint32_t b[2] = {1, uint32_t(i)}; // (i < 2^30: checked above)
        appendBigEndian(o, b, 2);
    });
    out.write("\n");
    if (ps.attributes.empty()) return;
    out.write("POINT_DATA " + n + "\nFIELD FieldData " + std::to_string(ps.attributes.size()) +
              "\n");
    for (const Attribute& a : ps.attributes) {
        bool wide = false;
        for (int64_t v : a.ints)
            wide = wide || v < INT32_MIN || v > INT32_MAX;
        const bool isFloat = a.type == AttributeType::Float;
        out.write(a.name + " " + std::to_string(a.components) + " " + n + " " +
                  (isFloat ? "float" : (wide ? "vtktypeint64" : "int")) + "\n");
        io::writeItems(out, a.size(), wide ? 8 : 4, [&](std::string& o, size_t k) {
            if (wide) {
                appendBigEndian64(o, uint64_t(a.ints[k]));
            } else {
                const uint32_t b = isFloat ? bitsOf(a.floats[k]) : bitsOf(int32_t(a.ints[k]));
                appendBigEndian(o, &b, 1);
            }
        });
        out.write("\n");
    }
}

} // namespace io_internal
} // namespace fluidsurf
