// VdbGrids.h - every grid of a .vdb held in memory, after our own walk of its structure
// (OpenVDB's reader trusts the file; see VdbCheck.cc). Shared by the points reader,
// readLevelSet and describeVdb.
#pragma once

#include <openvdb/openvdb.h>

#include <cstdint>
#include <string>
#include <vector>

namespace fluidsurf {
namespace io_internal {

/// InputError naming src for a file that is not a VDB, is truncated or corrupt. Grids the walk
/// cannot check (other tree types, frustum transforms) are left out and listed in skipped.
openvdb::GridPtrVecPtr readVdbGrids(const uint8_t* data, size_t size, const std::string& src,
                                    std::vector<std::string>* skipped = nullptr);
/// The same for a whole file's bytes, freed once checked: the check's copy is what OpenVDB
/// reads, so a file is held once, not twice, while its grids are built.
openvdb::GridPtrVecPtr readVdbGrids(std::vector<uint8_t>&& file, const std::string& src,
                                    std::vector<std::string>* skipped = nullptr);

} // namespace io_internal
} // namespace fluidsurf
