// DeviceCells.cuh - the cell index on the device (the twin of lib/src/neighbors/CellIndex.h):
// particles sorted by the Morton key of their cell, the occupied cells' keys and particle
// ranges, and an open-addressing hash table of the keys with the CPU's slot function, so a
// lookup finds exactly the cells the CPU finds.
#pragma once

#include "Morton.cuh"
#include "neighbors/CellSlot.h"

#include <cstdint>

namespace fluidsurf {
namespace cuda {

struct DeviceCells
{
    size_t count = 0;                   ///< particles
    size_t cellCount = 0;               ///< occupied cells
    float3* positions = nullptr;        ///< cell order
    float* radii = nullptr;             ///< cell order, or null (uniform radius)
    uint32_t* order = nullptr;          ///< cell order -> input index
    uint32_t* cellOf = nullptr;         ///< particle -> its cell
    unsigned long long* keys = nullptr; ///< ascending Morton keys of the occupied cells
    uint32_t* starts = nullptr;         ///< cellCount + 1 offsets
    unsigned long long* tableKeys = nullptr;
    uint32_t* tableCells = nullptr;
    unsigned long long tableMask = 0; ///< table size - 1 (a power of two)
    double cellSize = 0, origin[3] = {0, 0, 0};
    int dims[3] = {0, 0, 0};
};

constexpr unsigned long long kEmptyKey = ~0ull;

/// The CPU's slot function (neighbors/CellSlot.h, the same code).
__device__ __forceinline__ unsigned long long slotOf(unsigned long long key,
                                                     unsigned long long mask)
{
    return neighbors::cellSlot(key, mask);
}

/// Cell coordinate of a world position along an axis, clamped to [-1, dims] (CellIndex::cellCoord).
__device__ __forceinline__ long long cellCoord(const DeviceCells& c, double v, int axis)
{
    const double f = floor((v - c.origin[axis]) / c.cellSize);
    if (!(f >= 0)) return -1;
    if (f >= double(c.dims[axis])) return c.dims[axis];
    return (long long)f;
}

/// Index of cell (cx, cy, cz) among the occupied cells, or -1 (CellIndex::find).
__device__ __forceinline__ long long findCell(const DeviceCells& c, long long cx, long long cy,
                                              long long cz)
{
    if (cx < 0 || cy < 0 || cz < 0 || cx >= c.dims[0] || cy >= c.dims[1] || cz >= c.dims[2])
        return -1;
    const unsigned long long key = mortonKey(cx, cy, cz);
    for (unsigned long long slot = slotOf(key, c.tableMask);; slot = (slot + 1) & c.tableMask) {
        const unsigned long long k = c.tableKeys[slot];
        if (k == key) return c.tableCells[slot];
        if (k == kEmptyKey) return -1;
    }
}

} // namespace cuda
} // namespace fluidsurf
