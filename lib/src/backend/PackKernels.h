// PackKernels.h - the anisotropic kernels' table as it travels to the GPU (cuda::AnisotropicInput):
// a kernel's A', extent and weight go only where they differ from the kernel before it. A frame's
// interior kernels are all one sphere (anisotropy/KernelShapes.h stretches surface particles
// only), and in the cell index's order they come in runs, so on the generated 1M drop most of the
// 36 bytes a kernel would send stay here; the device unpacks them in a few microseconds.
#pragma once

#include "field/AnisotropicField.h"

#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace backend {

struct PackedKernels
{
    /// Bit j % 32 of word j / 32: kernel j's entry (its a, extent and weight, bit for bit) differs
    /// from kernel j - 1's; kernel 0's bit is set.
    std::vector<uint32_t> fresh;
    std::vector<uint32_t> freshBefore;    ///< per word: the bits set in the words before it
    std::vector<float> a, extent, weight; ///< the fresh kernels' entries, in order (weight: yt10's)
    size_t freshCount() const { return extent.size() / 3; }
};

/// table's kernels, packed; parallel over runs of kernels, the same result for any thread count.
PackedKernels packKernels(const field::AnisotropicKernels& table);

} // namespace backend
} // namespace fluidsurf
