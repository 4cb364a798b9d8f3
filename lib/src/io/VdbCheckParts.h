// VdbCheckParts.h - pieces of a .vdb that both walks (VdbCheck: files, grids and value trees;
// VdbPointBuffers: the leaf buffers of point grids) check the same way.
#pragma once

#include "io/ByteReader.h"

#include <cstdint>
#include <string>
#include <vector>

namespace fluidsurf {
namespace io_internal {

/// A length-prefixed string as OpenVDB writes names and type names.
std::string readVdbString(ByteReader& in, const char* what);

/// A MetaMap (count, then name, type name and value, each length-prefixed) copied to out
/// without the entries OpenVDB drops or only uses for delayed loading (types starting with
/// "__"). A value of a registered fixed-size type must have that size: OpenVDB reads sizeof(T)
/// whatever the length says, and would then read the rest of the grid from the wrong place.
void copyMetaMap(ByteReader& in, std::vector<uint8_t>& out, const char* what);

/// A blosc chunk of chunkBytes that must decompress to bytes: blosc trusts its own header, so
/// the sizes there must be these. padded: OpenVDB's attribute arrays and pages pad anything
/// under 128 bytes to 128 before compressing, and accept either size back.
void checkBloscChunk(ByteReader& in, const uint8_t* chunk, uint64_t chunkBytes, uint64_t bytes,
                     bool padded, const std::string& what);

} // namespace io_internal
} // namespace fluidsurf
