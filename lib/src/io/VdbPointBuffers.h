// VdbPointBuffers.h - the leaf buffers of a point grid walked before OpenVDB reads them (see
// VdbPointBuffers.cc).
#pragma once

#include "io/ByteReader.h"

#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace io_internal {

/// Walks a PointDataGrid's leaf buffers from in's position (right after the tree topology) to
/// their end, given each leaf's topology value mask in file order. InputError naming the source
/// and the byte offset for anything OpenVDB 10 would misread.
void walkPointBuffers(ByteReader& in, const std::vector<const uint8_t*>& leafMasks);

} // namespace io_internal
} // namespace fluidsurf
