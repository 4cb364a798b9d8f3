// CellSlot.h - where a cell's Morton key starts its search in the cell index's hash table
// (neighbors/CellIndex.h). Plain C++ that nvcc also compiles (like classify/ClassRule.h): the
// CUDA gather searches the table the CPU built (backend/CudaBackend.cc uploads it), and the
// device builds its own for its pipeline, so both sides must start every key at the same slot.
#pragma once

#include "util/HostDevice.h"

#include <stdint.h>

namespace fluidsurf {
namespace neighbors {

/// Keys equal but for their lowest kSlotBrickBits bits: a 4x4x4 brick of cells, consecutive in
/// Morton order.
constexpr int kSlotBrickBits = 6;

/// The first slot of key in a table of mask + 1 slots (a power of two), from which the search
/// goes on one slot at a time. A brick's keys start in one run of 64 slots, each at its place in
/// the brick, the run placed by a multiplicative hash of the brick. Why: classification and the
/// field's gather look up the 3 x 3 x 3 cells around each cell, cell after cell in Morton order.
/// With each key hashed on its own every new look-up was a cache miss in a table of tens of MB
/// (a fifth of classification's own time on the 13.1M drop); a brick's look-ups now share a few
/// cache lines. The search still goes one slot at a time, so it ends at any load under 1.
FLUIDSURF_HD inline uint64_t cellSlot(uint64_t key, uint64_t mask)
{
    const uint64_t brick = key >> kSlotBrickBits, place = key & ((1u << kSlotBrickBits) - 1);
    return ((brick * 0x9e3779b97f4a7c15ull) >> 17 << kSlotBrickBits | place) & mask;
}

} // namespace neighbors
} // namespace fluidsurf
