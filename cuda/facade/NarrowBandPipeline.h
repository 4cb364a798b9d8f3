// NarrowBandPipeline.h - the whole narrow-band field on the GPU (host facade, no CUDA syntax):
// upload, Morton keys, radix sort, cells, classification, band marking and the SSP07 / ZB05
// gather, on one stream, producing leaf blocks (origin + active bits + 512 values) that the host
// turns into a FloatTree. Every stage repeats the CPU's arithmetic (cells, classes, band, and the
// field's picks, order, lanes and fused steps: FieldGather.h), so the grid has the CPU's active
// voxels and values.
//
// Usage: upload() returns the particles' bounds; the host derives the cell grid from them with
// its own arithmetic (neighbors::cellGrid); run() does the rest. The particles stay on the device
// for evaluate() (band completion) until the object is destroyed.
#pragma once

#include "facade/FieldGather.h"
#include <fluidsurf/Vec3.h>

#include <cstddef>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

namespace fluidsurf {
namespace cuda {

struct ClassCounts
{
    size_t interior = 0, surface = 0, splash = 0, isolated = 0;
};

struct PipelineSettings
{
    // Cell grid (neighbors::CellIndex): cell size and the corner and size of the grid.
    double cellSize = 0, cellOrigin[3] = {0, 0, 0};
    uint32_t cellDims[3] = {0, 0, 0};
    // Classification (classify/Classify.h), constants computed on the host like the CPU does.
    float h2 = 0;
    double smoothingLength = 0, poly6 = 0, gradientScale = 0;
    float uniformVolume = 0;
    int splashNeighbours = 3, surfaceNeighbours = 0;
    double colorFieldThreshold = 0, colorGradientThreshold = 0;
    bool keepIsolated = false;
    // Band (narrowband/NarrowBand.h): half width in world units.
    double bandWidth = 0;
    FieldSettings field;
    /// Called on the host with the classes' counts before the band is marked: the host's memory
    /// check (an exception thrown here ends run() with it, before the band is built).
    std::function<void(const ClassCounts&)> beforeBand;
};

struct LeafBlocks
{
    std::vector<int32_t> origins; ///< 3 per leaf
    std::vector<uint64_t> masks;  ///< 8 per leaf: word x, bit y * 8 + z
    std::vector<float>
        values; ///< the active voxels only, leaf after leaf, in OpenVDB's voxel order
    size_t size() const { return origins.size() / 3; }
};

class NarrowBandPipeline
{
public:
    /// stream: a cudaStream_t as void*, or null for a stream of the pipeline's own.
    explicit NarrowBandPipeline(void* stream = nullptr);
    ~NarrowBandPipeline();
    NarrowBandPipeline(const NarrowBandPipeline&) = delete;
    NarrowBandPipeline& operator=(const NarrowBandPipeline&) = delete;

    /// Copy n particles (radii may be null: uniform radius) to the device; their bounds come back.
    void upload(const Vec3f* positions, const float* radii, size_t n, Vec3f& lo, Vec3f& hi);

    /// Sort through gather; the band's leaf blocks come back (leaves in ascending x, y, z order).
    LeafBlocks run(const PipelineSettings& settings);

    /// After run(): per-class counts, and the input indices of the isolated particles (ascending).
    const ClassCounts& classCounts() const;
    const std::vector<uint32_t>& isolatedParticles() const;

    /// After run(): phi at the active voxels of more leaves (band completion), as gatherField
    /// returns them (active voxels only, leaf after leaf).
    std::vector<float> evaluate(const int32_t* origins, const uint64_t* masks, size_t leafCount);

    /// GPU time per stage (CUDA events, milliseconds), run() and evaluate() calls in order.
    const std::vector<std::pair<std::string, double>>& stageMs() const;
    /// Peak device memory the pipeline held, bytes.
    size_t peakBytes() const;

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace cuda
} // namespace fluidsurf
