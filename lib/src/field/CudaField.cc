// CudaField.cc - FloatTree leaves <-> the CUDA gather's plain arrays. Without the CUDA backend
// (FLUIDSURF_HAS_CUDA unset) the entry points report that clearly.
#include "field/CudaField.h"

#include <fluidsurf/Error.h>

#ifdef FLUIDSURF_HAS_CUDA
#include <fluidsurf/cuda/Device.h>
#include <fluidsurf/cuda/FieldGather.h>

#include <openvdb/tree/LeafManager.h>
#endif

namespace fluidsurf {
namespace field {

#ifdef FLUIDSURF_HAS_CUDA

bool cudaUsable(std::string* reason, std::string* deviceName)
{
    const cuda::DeviceInfo info = cuda::openDevice();
    if (reason) *reason = info.reason;
    if (deviceName) *deviceName = info.name;
    return info.usable;
}

size_t evaluateFieldCuda(openvdb::FloatTree& tree, const neighbors::CellIndex& particles, const Params& params,
                         RasterizeStats& stats)
{
    std::string reason, name;
    if (!cudaUsable(&reason, &name)) throw Error("CUDA was requested but there is no usable GPU: " + reason);
    using LeafT = openvdb::FloatTree::LeafNodeType;
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(tree);
    const size_t n = leaves.leafCount();
    std::vector<int32_t> origins(3 * n);
    std::vector<uint64_t> active(8 * n);
    size_t evaluations = 0;
    for (size_t i = 0; i < n; ++i) {
        const LeafT& leaf = leaves.leaf(i);
        for (int a = 0; a < 3; ++a) origins[3 * i + a] = leaf.origin()[a];
        for (int w = 0; w < 8; ++w) active[8 * i + w] = leaf.getValueMask().template getWord<uint64_t>(w);
        evaluations += leaf.onVoxelCount();
    }
    cuda::GatherInput in;
    in.positions = particles.positions.data();
    in.radii = particles.radii.empty() ? nullptr : particles.radii.data();
    in.particleCount = particles.size();
    in.cellKeys = particles.keys.data();
    in.cellStarts = particles.starts.data();
    in.cellCount = particles.cellCount();
    in.cellSize = particles.cellSize;
    for (int a = 0; a < 3; ++a) in.cellOrigin[a] = particles.origin[a], in.cellDims[a] = particles.dims[a];
    in.leafOrigins = origins.data();
    in.leafActive = active.data();
    in.leafCount = n;
    in.voxelSize = params.voxelSize;
    in.influenceRadius = params.influenceRadius;
    in.radius = params.radius;
    in.tLow = params.tLow, in.tHigh = params.tHigh;
    in.background = float(params.background());
    in.ssp07 = params.field == FieldKind::Ssp07;
    cuda::GatherTimes times;
    const std::vector<float> values = cuda::gatherField(in, &times);
    leaves.foreach([&](LeafT& leaf, size_t i) {
        for (auto v = leaf.beginValueOn(); v; ++v) v.setValue(values[i * 512 + v.pos()]);
    });
    stats.device = name;
    stats.gpuStages = {{"upload", times.uploadMs * 1e-3}, {"gather kernel", times.kernelMs * 1e-3},
                       {"download", times.downloadMs * 1e-3}};
    stats.gpuBytes = times.deviceBytes;
    return evaluations;
}

#else

bool cudaUsable(std::string* reason, std::string*)
{
    if (reason) *reason = "this build of fluidsurf has no CUDA backend";
    return false;
}

size_t evaluateFieldCuda(openvdb::FloatTree&, const neighbors::CellIndex&, const Params&, RasterizeStats&)
{
    throw Error("CUDA was requested but this build of fluidsurf has no CUDA backend (rebuild with nvcc)");
}

#endif

} // namespace field
} // namespace fluidsurf
