// CudaField.cc - FloatTree leaves <-> the CUDA backend's leaf blocks (origin + 8 mask words +
// 512 values), both ways in parallel.
#include "field/CudaField.h"

#include <fluidsurf/Error.h>

#ifdef FLUIDSURF_HAS_CUDA
#include "classify/Classify.h"
#include "narrowband/CompleteBand.h"

#include <fluidsurf/cuda/Device.h>
#include <fluidsurf/cuda/FieldGather.h>
#include <fluidsurf/cuda/NarrowBandPipeline.h>

#include <openvdb/tree/LeafManager.h>

#include <tbb/parallel_for.h>

#include <cmath>
#endif

namespace fluidsurf {
namespace field {

#ifdef FLUIDSURF_HAS_CUDA

namespace {

using LeafT = openvdb::FloatTree::LeafNodeType;

/// The values of every active voxel of tree from compute(origins, masks, leafCount), which
/// returns 512 values per leaf. Returns the number of active voxels.
template <typename Compute> size_t fillActiveVoxels(openvdb::FloatTree& tree, Compute&& compute)
{
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(tree);
    const size_t n = leaves.leafCount();
    std::vector<int32_t> origins(3 * n);
    std::vector<uint64_t> masks(8 * n);
    leaves.foreach ([&](const LeafT& leaf, size_t i) {
        for (int a = 0; a < 3; ++a)
            origins[3 * i + a] = leaf.origin()[a];
        for (int w = 0; w < 8; ++w)
            masks[8 * i + w] = leaf.getValueMask().template getWord<uint64_t>(w);
    });
    const std::vector<float> values = compute(origins.data(), masks.data(), n);
    leaves.foreach ([&](LeafT& leaf, size_t i) {
        for (auto v = leaf.beginValueOn(); v; ++v)
            v.setValue(values[i * 512 + v.pos()]);
    });
    return tree.activeVoxelCount();
}

cuda::FieldSettings fieldSettings(const Params& params)
{
    cuda::FieldSettings f;
    f.voxelSize = params.voxelSize;
    f.influenceRadius = params.influenceRadius;
    f.radius = params.radius;
    f.tLow = params.tLow, f.tHigh = params.tHigh;
    f.background = float(params.background());
    f.ssp07 = params.field == FieldKind::Ssp07;
    return f;
}

/// A tree from leaf blocks: leaves built in parallel, then linked in (cheap, serial).
openvdb::FloatTree::Ptr treeFromBlocks(const cuda::LeafBlocks& blocks, float background)
{
    const size_t n = blocks.size();
    // Where each leaf's active values start in the compact array.
    std::vector<size_t> offsets(n + 1, 0);
    for (size_t i = 0; i < n; ++i) {
        size_t count = 0;
        for (int w = 0; w < 8; ++w)
            count += size_t(__builtin_popcountll(blocks.masks[8 * i + w]));
        offsets[i + 1] = offsets[i] + count;
    }
    if (offsets[n] != blocks.values.size())
        throw Error("CUDA pipeline: leaf blocks and values disagree");
    std::vector<LeafT*> built(n);
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, n, 64), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                const openvdb::Coord origin(blocks.origins[3 * i], blocks.origins[3 * i + 1],
                                            blocks.origins[3 * i + 2]);
                auto* leaf = new LeafT(origin, background);
                float* buffer = leaf->buffer().data();
                LeafT::NodeMaskType mask;
                const float* value = &blocks.values[offsets[i]];
                for (int w = 0; w < 8; ++w) {
                    const uint64_t word = blocks.masks[8 * i + w];
                    mask.template getWord<uint64_t>(w) = word;
                    for (uint64_t bits = word; bits; bits &= bits - 1)
                        buffer[64 * w + __builtin_ctzll(bits)] = *value++;
                }
                leaf->setValueMask(mask);
                built[i] = leaf;
            }
        });
    auto tree = std::make_shared<openvdb::FloatTree>(background);
    for (LeafT* leaf : built)
        tree->addLeaf(leaf); // the tree takes ownership
    return tree;
}

} // namespace

bool cudaUsable(std::string* reason, std::string* deviceName)
{
    const cuda::DeviceInfo info = cuda::openDevice();
    if (reason) *reason = info.reason;
    if (deviceName) *deviceName = info.name;
    return info.usable;
}

size_t evaluateFieldCuda(openvdb::FloatTree& tree, const neighbors::CellIndex& particles,
                         const Params& params, RasterizeStats& stats)
{
    std::string reason, name;
    if (!cudaUsable(&reason, &name))
        throw Error("CUDA was requested but there is no usable GPU: " + reason);
    cuda::GatherTimes times;
    const size_t evaluations =
        fillActiveVoxels(tree, [&](const int32_t* origins, const uint64_t* masks, size_t n) {
            cuda::GatherInput in;
            in.positions = particles.positions.data();
            in.radii = particles.radii.empty() ? nullptr : particles.radii.data();
            in.particleCount = particles.size();
            in.tableKeys = particles.tableKeys.data();
            in.tableCells = particles.tableCells.data();
            in.tableSize = particles.tableKeys.size();
            in.cellStarts = particles.starts.data();
            in.cellCount = particles.cellCount();
            in.cellSize = particles.cellSize;
            for (int a = 0; a < 3; ++a)
                in.cellOrigin[a] = particles.origin[a], in.cellDims[a] = particles.dims[a];
            in.leafOrigins = origins;
            in.leafActive = masks;
            in.leafCount = n;
            in.field = fieldSettings(params);
            return cuda::gatherField(in, &times);
        });
    stats.device = name;
    stats.gpuStages = {{"upload", times.uploadMs * 1e-3},
                       {"gather", times.kernelMs * 1e-3},
                       {"download", times.downloadMs * 1e-3}};
    stats.gpuBytes = times.deviceBytes;
    return evaluations;
}

openvdb::FloatTree::Ptr
rasterizeNarrowBandCuda(const std::vector<Vec3f>& positions, const std::vector<float>& radii,
                        const Params& params, double bandWidth, RasterizeStats& stats,
                        std::vector<uint32_t>& isolated, const StageDone& stageDone)
{
    std::string reason, name;
    if (!cudaUsable(&reason, &name))
        throw Error("CUDA was requested but there is no usable GPU: " + reason);
    if (positions.size() >= (size_t(1) << 32) - 1)
        throw ValueError("more than 2^32 - 2 particles in one frame");
    cuda::NarrowBandPipeline pipeline;
    Vec3f lo, hi;
    pipeline.upload(positions.data(), radii.empty() ? nullptr : radii.data(), positions.size(), lo,
                    hi);
    // Leaf keys on the device hold 21 bits per axis around leaf 0.
    const double limit = double(1 << 20) * 8 * params.voxelSize;
    for (int a = 0; a < 3; ++a)
        if (!(std::abs(double(lo[a]) - bandWidth) < limit - 16 * params.voxelSize &&
              std::abs(double(hi[a]) + bandWidth) < limit - 16 * params.voxelSize))
            return nullptr;
    stageDone("upload");

    cuda::PipelineSettings s;
    s.cellSize = std::min(params.influenceRadius, params.smoothingLength);
    BBox3f box;
    box.expand(lo), box.expand(hi);
    neighbors::cellGrid(box, s.cellSize, s.cellOrigin, s.cellDims);
    const classify::KernelConstants k = classify::kernelConstants(params);
    s.h2 = k.h2;
    s.smoothingLength = k.h, s.poly6 = k.poly6, s.gradientScale = k.gradientScale;
    s.uniformVolume = float(k.uniformVolume);
    s.splashNeighbours = params.splashNeighbours, s.surfaceNeighbours = params.surfaceNeighbours;
    s.colorFieldThreshold = params.colorFieldThreshold,
    s.colorGradientThreshold = params.colorGradientThreshold;
    s.keepIsolated = params.keepIsolated;
    s.bandWidth = bandWidth;
    s.field = fieldSettings(params);
    const cuda::LeafBlocks blocks = pipeline.run(s);
    const cuda::ClassCounts& counts = pipeline.classCounts();
    stats.interior = counts.interior, stats.surface = counts.surface;
    stats.splash = counts.splash, stats.isolated = counts.isolated;
    if (!params.keepIsolated) isolated = pipeline.isolatedParticles();
    stageDone("device field");

    openvdb::FloatTree::Ptr tree = treeFromBlocks(blocks, s.field.background);
    stats.fieldEvaluations = tree->activeVoxelCount();
    stageDone("vdb build");

    stats.bandCompletion = narrowband::completeBand(*tree, params, [&](openvdb::FloatTree& grown) {
        fillActiveVoxels(grown, [&](const int32_t* origins, const uint64_t* masks, size_t n) {
            return pipeline.evaluate(origins, masks, n);
        });
    });
    stats.fieldEvaluations += stats.bandCompletion;
    stageDone("complete band");

    stats.device = name;
    stats.gpuStages.clear();
    for (const auto& st : pipeline.stageMs())
        stats.gpuStages.push_back({st.first, st.second * 1e-3});
    stats.gpuBytes = pipeline.peakBytes();
    return tree;
}

#else

bool cudaUsable(std::string* reason, std::string*)
{
    if (reason) *reason = "this build of fluidsurf has no CUDA backend";
    return false;
}

size_t evaluateFieldCuda(openvdb::FloatTree&, const neighbors::CellIndex&, const Params&,
                         RasterizeStats&)
{
    throw Error(
        "CUDA was requested but this build of fluidsurf has no CUDA backend (rebuild with nvcc)");
}

openvdb::FloatTree::Ptr rasterizeNarrowBandCuda(const std::vector<Vec3f>&,
                                                const std::vector<float>&, const Params&, double,
                                                RasterizeStats&, std::vector<uint32_t>&,
                                                const StageDone&)
{
    throw Error(
        "CUDA was requested but this build of fluidsurf has no CUDA backend (rebuild with nvcc)");
}

#endif

} // namespace field
} // namespace fluidsurf
