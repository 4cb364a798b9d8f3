// CudaField.h - the field stage on the GPU (Params::device): the active voxels of a FloatTree
// are handed to the CUDA backend as leaf blocks (origin + active bits), with the particles of
// the cell index, and the 512 values per leaf come back into the tree.
#pragma once

#include "neighbors/CellIndex.h"

#include <fluidsurf/Params.h>
#include <fluidsurf/Rasterize.h>

#include <openvdb/openvdb.h>

namespace fluidsurf {
namespace field {

/// Whether this build has the CUDA backend and a usable GPU; reason says why not. The first call
/// creates the CUDA context (0.1-0.3 s), so the pipeline makes it on a thread of its own while
/// the CPU stages run.
bool cudaUsable(std::string* reason = nullptr, std::string* deviceName = nullptr);

/// Like evaluateField, on the GPU; GPU timings and memory go into stats. Error when the build has
/// no CUDA backend or there is no usable GPU.
size_t evaluateFieldCuda(openvdb::FloatTree& tree, const neighbors::CellIndex& particles, const Params& params,
                         RasterizeStats& stats);

} // namespace field
} // namespace fluidsurf
