// VdbWrite.h - every .vdb this library writes (level sets, point grids) goes through here:
// OpenVDB's archive format written into a checked stream over an AtomicFile's temporary. Its
// io::File writes through an std::ofstream whose failures it never checks, so a full disk
// committed a truncated file with success (issue 63); here each write is checked, and a
// failure removes the temporary, keeps an older file and names the output.
#pragma once

#include <openvdb/openvdb.h>

#include <cstdint>
#include <string>

namespace fluidsurf {
namespace io_internal {

/// Write grids to path atomically with the given compression flags (openvdb::io::COMPRESS_*).
/// uuidFromContent: the header's UUID becomes a hash of the bytes after it (equal grids give
/// equal files). OutputError naming path when a byte cannot be written or synced.
void writeVdbFile(const openvdb::GridCPtrVec& grids, const std::string& path, uint32_t compression,
                  bool uuidFromContent);

} // namespace io_internal
} // namespace fluidsurf
