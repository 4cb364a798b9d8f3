// PlyHeader.cc - the PLY header, shared by the particle and mesh readers.
#include "io/PlyHeader.h"

#include "io/TextParse.h"

#include <cstring>

namespace fluidsurf {
namespace io_internal {

bool plyType(const std::string& n, PlyType& t)
{
    if (n == "char" || n == "int8")
        t = {1, false, true};
    else if (n == "uchar" || n == "uint8")
        t = {1, false, false};
    else if (n == "short" || n == "int16")
        t = {2, false, true};
    else if (n == "ushort" || n == "uint16")
        t = {2, false, false};
    else if (n == "int" || n == "int32")
        t = {4, false, true};
    else if (n == "uint" || n == "uint32")
        t = {4, false, false};
    else if (n == "float" || n == "float32")
        t = {4, true, true};
    else if (n == "double" || n == "float64")
        t = {8, true, true};
    else
        return false;
    return true;
}

PlyHeader readPlyHeader(ByteReader& in)
{
    const uint8_t* data = in.cursor();
    if (in.remaining() < 4 || std::memcmp(data, "ply", 3) != 0 ||
        (data[3] != '\n' && data[3] != '\r'))
        in.failAt(0, "not a PLY file (missing 'ply' magic line)");
    in.line("magic");
    PlyHeader h;
    bool haveFormat = false;
    std::vector<PlyElement>& elements = h.elements;
    while (true) {
        const auto w = splitWords(in.line("the PLY header"));
        if (w.empty() || w[0] == "comment" || w[0] == "obj_info") continue;
        if (w[0] == "end_header") break;
        if (w[0] == "format") {
            if (w.size() < 3) in.fail("incomplete format line");
            if (w[1] == "ascii")
                h.format = PlyFormat::Ascii;
            else if (w[1] == "binary_little_endian")
                h.format = PlyFormat::LittleEndian;
            else if (w[1] == "binary_big_endian")
                h.format = PlyFormat::BigEndian;
            else
                in.fail("unknown PLY format '" + w[1].substr(0, 40) + "'");
            haveFormat = true;
        } else if (w[0] == "element") {
            if (w.size() < 3) in.fail("incomplete element line");
            elements.push_back({w[1], parseCount(in, w[2], "element count"), {}});
        } else if (w[0] == "property") {
            if (elements.empty()) in.fail("property before any element");
            PlyProperty p;
            if (w.size() >= 5 && w[1] == "list") {
                p.isList = true;
                if (!plyType(w[2], p.countType) || !plyType(w[3], p.type) || p.countType.isFloat)
                    in.fail("bad list property types '" + w[2] + " " + w[3] + "'");
                p.name = w[4];
            } else {
                if (w.size() < 3 || !plyType(w[1], p.type)) in.fail("bad property line");
                p.name = w[2];
            }
            elements.back().props.push_back(p);
        } else {
            in.fail("unexpected PLY header line '" + w[0].substr(0, 40) + "'");
        }
    }
    if (!haveFormat) in.fail("PLY header has no format line");
    return h;
}

double loadPlyNumber(const uint8_t* p, const PlyType& t, bool be)
{
    if (t.isFloat) return t.size == 4 ? double(loadAs<float>(p, be)) : loadAs<double>(p, be);
    switch (t.size) {
    case 1:
        return t.isSigned ? double(int8_t(*p)) : double(*p);
    case 2:
        return t.isSigned ? double(loadAs<int16_t>(p, be)) : double(loadAs<uint16_t>(p, be));
    default:
        return t.isSigned ? double(loadAs<int32_t>(p, be)) : double(loadAs<uint32_t>(p, be));
    }
}

double readPlyValue(ByteReader& in, const PlyType& t, PlyFormat format, const char* what)
{
    if (format == PlyFormat::Ascii) return readAsciiNumber(in, what);
    return loadPlyNumber(in.take(t.size, what), t, format == PlyFormat::BigEndian);
}

} // namespace io_internal
} // namespace fluidsurf
