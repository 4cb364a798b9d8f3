// LeafKeys.cuh - leaves found by their 64-bit keys (21 bits a leaf axis) in a sorted key array:
// the narrow band's masks (NarrowBand.cu) and marching cubes' neighbours (MarchingCubes.cu).
#pragma once

#include <cstddef>

namespace fluidsurf {
namespace cuda {

/// The position of key in the ascending keys[0, count), or -1 where it is not there.
__device__ __forceinline__ long long findLeaf(const unsigned long long* keys, size_t count,
                                              unsigned long long key)
{
    size_t lo = 0, hi = count;
    while (lo < hi) {
        const size_t mid = (lo + hi) / 2;
        if (keys[mid] < key)
            lo = mid + 1;
        else
            hi = mid;
    }
    return lo < count && keys[lo] == key ? (long long)lo : -1;
}

} // namespace cuda
} // namespace fluidsurf
