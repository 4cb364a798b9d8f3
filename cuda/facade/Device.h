// Device.h - host facade of the CUDA backend (no CUDA syntax here, so any C++ compiler can
// include it). Every CUDA call is checked; failures throw fluidsurf::Error naming the call and
// file:line. Entry points take an optional stream (a cudaStream_t passed as void*).
#pragma once

#include <fluidsurf/Vec3.h>

#include <cstdint>
#include <string>
#include <vector>

namespace fluidsurf {
namespace cuda {

struct DeviceInfo
{
    bool usable = false;
    std::string reason; ///< why not usable (no driver, no device, ...)
    std::string name;   ///< e.g. "NVIDIA H100 80GB HBM3"
    int computeMajor = 0, computeMinor = 0;
    size_t memoryBytes = 0;
};

/// The first CUDA device, or why there is none. Never throws.
DeviceInfo queryDevice();

/// queryDevice() plus the CUDA context created, once per process (later calls return the same
/// answer at no cost). Never throws.
DeviceInfo openDevice();

/// Z-order (Morton) code of the cell of size cellSize holding each position, cells counted from
/// origin, 21 bits per axis interleaved as x0 y0 z0 x1 y1 z1 ... (x in the lowest bit).
/// Coordinates below origin or beyond 2^21 cells are clamped. Runs on the GPU.
std::vector<uint64_t> mortonCodes(const Vec3f* positions, size_t count, const Vec3f& origin,
                                  float cellSize, void* stream = nullptr);

} // namespace cuda
} // namespace fluidsurf
