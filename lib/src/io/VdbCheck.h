// VdbCheck.h - a .vdb walked node by node before OpenVDB decodes it (see VdbCheck.cc).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace fluidsurf {
namespace io_internal {

/// What OpenVDB may read of a file: a normalised copy holding the grids whose every byte was
/// checked, each right after its descriptor with offsets that match.
struct CheckedVdb
{
    std::vector<uint8_t> bytes;
    std::vector<std::string> skipped; ///< "name (type): why" for each grid left out
};

/// InputError naming src (and the byte offset) for anything OpenVDB 10 would misread: counts or
/// sizes the file cannot hold, masks that disagree, unknown compression, chunk sizes that do not
/// match what a node needs, offsets that do not match the grid's real end.
CheckedVdb checkVdb(const uint8_t* data, size_t size, const std::string& src);

} // namespace io_internal
} // namespace fluidsurf
