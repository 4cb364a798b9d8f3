// PlyHeader.h - the PLY header and value types, shared by the particle reader (PlyIO.cc) and
// the mesh reader (MeshReader.cc): magic, format, elements and their (list) properties.
#pragma once

#include "io/ByteReader.h"

#include <cstdint>
#include <string>
#include <vector>

namespace fluidsurf {
namespace io_internal {

struct PlyType
{
    size_t size = 0;
    bool isFloat = false, isSigned = false;
};

/// PLY's type names ("uchar", "float32", ...); false for an unknown one.
bool plyType(const std::string& name, PlyType& type);

struct PlyProperty
{
    std::string name;
    PlyType type;
    bool isList = false;
    PlyType countType;
};

struct PlyElement
{
    std::string name;
    uint64_t count = 0;
    std::vector<PlyProperty> props;
};

enum class PlyFormat { Ascii, LittleEndian, BigEndian };

struct PlyHeader
{
    PlyFormat format = PlyFormat::Ascii;
    std::vector<PlyElement> elements;
};

/// Magic line through end_header; in is left at the body. InputError naming what is wrong.
PlyHeader readPlyHeader(ByteReader& in);

/// One binary value.
double loadPlyNumber(const uint8_t* p, const PlyType& t, bool bigEndian);

/// One value of the body in the header's format (ascii text or binary).
double readPlyValue(ByteReader& in, const PlyType& t, PlyFormat format, const char* what);

} // namespace io_internal
} // namespace fluidsurf
