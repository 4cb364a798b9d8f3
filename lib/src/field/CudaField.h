// CudaField.h - the field on the GPU (Params::device), two ways:
//  - rasterizeNarrowBandCuda: the whole narrow band on the device (sort, classify, band, gather;
//    cuda/NarrowBandPipeline), leaf blocks back into a FloatTree in parallel, and band
//    completion with the frontier found on the host and its new voxels evaluated on the device.
//  - evaluateFieldCuda: only the gather, over a tree built on the CPU (gather-full).
// Without the CUDA backend (FLUIDSURF_HAS_CUDA unset) the entry points say so clearly.
#pragma once

#include "neighbors/CellIndex.h"

#include <fluidsurf/Params.h>
#include <fluidsurf/ParticleSet.h>
#include <fluidsurf/Rasterize.h>

#include <openvdb/openvdb.h>

#include <functional>
#include <vector>

namespace fluidsurf {
namespace field {

/// Whether this build has the CUDA backend and a usable GPU; reason says why not. The first call
/// creates the CUDA context (0.1-0.3 s); later calls return the same answer at no cost.
bool cudaUsable(std::string* reason = nullptr, std::string* deviceName = nullptr);

/// Like evaluateField, on the GPU; GPU timings and memory go into stats. Error when the build has
/// no CUDA backend or there is no usable GPU.
size_t evaluateFieldCuda(openvdb::FloatTree& tree, const neighbors::CellIndex& particles,
                         const Params& params, RasterizeStats& stats);

/// The completed narrow band of the particles (radii: per particle, or empty), computed on the
/// GPU: the same active voxels as the CPU path, values within ~1e-5 r. Fills stats (classes,
/// evaluations, completion, GPU stages and memory) and isolated (input indices, ascending, when
/// not kept). stageDone(name) is called as each host stage ends. Returns null, having done
/// nothing to stats, when the frame does not fit the device's leaf keys (more than 2^20 leaves
/// from the origin along an axis); the caller then takes the CPU stages.
using StageDone = std::function<void(const char*)>;
openvdb::FloatTree::Ptr
rasterizeNarrowBandCuda(const std::vector<Vec3f>& positions, const std::vector<float>& radii,
                        const Params& params, double bandWidth, RasterizeStats& stats,
                        std::vector<uint32_t>& isolated, const StageDone& stageDone);

} // namespace field
} // namespace fluidsurf
