// VdbGrids.h - every grid of a .vdb held in memory, after our own structure checks (OpenVDB's
// reader trusts the file; see VdbPointsIO.cc). Shared by the points reader and readLevelSet.
#pragma once

#include <openvdb/openvdb.h>

#include <cstdint>
#include <string>

namespace fluidsurf {
namespace io_internal {

/// InputError naming src for a file that is not a VDB, is truncated or corrupt.
openvdb::GridPtrVecPtr readVdbGrids(const uint8_t* data, size_t size, const std::string& src);

} // namespace io_internal
} // namespace fluidsurf
