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
/// grid: a grid's own metadata, where the names OpenVDB sets itself must have its types.
void copyMetaMap(ByteReader& in, std::vector<uint8_t>& out, const char* what, bool grid = false);

/// A blosc chunk of chunkBytes that must decompress to bytes: blosc trusts its own header, so
/// the sizes there must be these. padded: OpenVDB's attribute arrays and pages pad anything
/// under 128 bytes to 128 before compressing, and accept either size back.
void checkBloscChunk(ByteReader& in, const uint8_t* chunk, uint64_t chunkBytes, uint64_t bytes,
                     bool padded, const std::string& what);

/// Decompresses a chunk checkBloscChunk accepted, into scratch, and fails unless blosc gives
/// back every byte its header promises. Point grids only: OpenVDB's point reader throws half-way
/// through its passes on data blosc cannot decode, and its paged state does not survive that
/// (leaked pages, double frees); a level set's reader throws cleanly, and decoding its chunks
/// twice would cost `mesh` its read time again.
void decodeBloscChunk(ByteReader& in, const uint8_t* chunk, std::vector<uint8_t>& scratch,
                      const std::string& what);

/// The same for a zip chunk of chunkBytes that must inflate to exactly bytes (the topology of a
/// point grid written with zip compression).
void decodeZipChunk(ByteReader& in, const uint8_t* chunk, uint64_t chunkBytes, uint64_t bytes,
                    std::vector<uint8_t>& scratch, const std::string& what);

} // namespace io_internal
} // namespace fluidsurf
