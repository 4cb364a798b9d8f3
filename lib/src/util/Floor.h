// Floor.h - floor to an integer without libm: std::floor is a library call on baseline x86-64
// (the build targets no SSE4.1), which the hot loops that bin points by floor felt (the field's
// slabs, decimation's blocks: three calls a triangle and pass). nvcc compiles it too (the CUDA
// gather bins particles as the CPU does: field/GatherLayout.h).
#pragma once

#include "util/HostDevice.h"

#include <cstdint>

namespace fluidsurf {
namespace util {

/// floor(v), exactly, for |v| < 2^62 (v not NaN).
FLUIDSURF_HD inline int64_t floorOf(double v)
{
    const int64_t i = int64_t(v); // towards zero
    return i - (double(i) > v);
}

} // namespace util
} // namespace fluidsurf
