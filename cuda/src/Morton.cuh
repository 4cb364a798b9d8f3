// Morton.cuh - Z-order bit spreading on the device, shared by the Morton-code and gather kernels
// (the CPU twin is neighbors::mortonKey: x in the lowest bit, 21 bits per axis).
#pragma once

namespace fluidsurf {
namespace cuda {

/// Spread the low 21 bits of v so that bit i moves to bit 3i.
__device__ __forceinline__ unsigned long long spreadBits(unsigned long long v)
{
    v &= 0x1fffff;
    v = (v | (v << 32)) & 0x001f00000000ffffull;
    v = (v | (v << 16)) & 0x001f0000ff0000ffull;
    v = (v | (v << 8)) & 0x100f00f00f00f00full;
    v = (v | (v << 4)) & 0x10c30c30c30c30c3ull;
    v = (v | (v << 2)) & 0x1249249249249249ull;
    return v;
}

/// The Morton key of cell (cx, cy, cz).
__device__ __forceinline__ unsigned long long
mortonKey(unsigned long long cx, unsigned long long cy, unsigned long long cz)
{
    return spreadBits(cx) | spreadBits(cy) << 1 | spreadBits(cz) << 2;
}

} // namespace cuda
} // namespace fluidsurf
