// NarrowBandPipeline.cu - runs the device stages (Stages.cuh) in order on one stream and moves
// the leaf blocks back (see fluidsurf/cuda/NarrowBandPipeline.h).
#include "facade/NarrowBandPipeline.h"

#include "Stages.cuh"

#include <algorithm>

namespace fluidsurf {
namespace cuda {

struct NarrowBandPipeline::Impl
{
    std::unique_ptr<Stream> ownStream;
    cudaStream_t stream = nullptr;
    std::unique_ptr<DeviceMemory> mem;
    const float3* inputPositions = nullptr;
    const float* inputRadii = nullptr;
    size_t count = 0;
    DeviceCells cells;
    field::FieldConstants constants;
    double voxelSize = 0;
    bool ran = false;
    ClassCounts counts;
    std::vector<uint32_t> isolated;
    std::vector<std::pair<std::string, double>> stages;

    void collect(const StageEvents& events)
    {
        for (const auto& s : events.stages())
            stages.push_back(s);
    }
};

NarrowBandPipeline::NarrowBandPipeline(void* stream) : mImpl(new Impl)
{
    mImpl->ownStream.reset(new Stream(stream));
    mImpl->stream = mImpl->ownStream->get();
    // Keep freed device memory in the pool between stages instead of handing it back to the
    // driver at every synchronisation (the destructor trims it).
    cudaMemPool_t pool;
    int device = 0;
    FLUIDSURF_CUDA_CHECK(cudaGetDevice(&device));
    FLUIDSURF_CUDA_CHECK(cudaDeviceGetDefaultMemPool(&pool, device));
    uint64_t threshold = ~uint64_t(0);
    FLUIDSURF_CUDA_CHECK(
        cudaMemPoolSetAttribute(pool, cudaMemPoolAttrReleaseThreshold, &threshold));
    mImpl->mem.reset(new DeviceMemory(mImpl->stream));
}

NarrowBandPipeline::~NarrowBandPipeline()
{
    mImpl->mem.reset(); // frees on the stream and waits
    mImpl->ownStream.reset();
    // Hand the pool's memory back: a tool that links the library keeps its GPU memory.
    cudaMemPool_t pool;
    int device = 0;
    if (cudaGetDevice(&device) == cudaSuccess &&
        cudaDeviceGetDefaultMemPool(&pool, device) == cudaSuccess)
        cudaMemPoolTrimTo(pool, 0);
}

void NarrowBandPipeline::upload(const Vec3f* positions, const float* radii, size_t n, Vec3f& lo,
                                Vec3f& hi)
{
    static_assert(sizeof(Vec3f) == sizeof(float3), "Vec3f must be three packed floats");
    Impl& m = *mImpl;
    StageEvents events(m.stream);
    m.count = n;
    m.inputPositions = m.mem->upload(reinterpret_cast<const float3*>(positions), n);
    m.inputRadii = radii ? m.mem->upload(radii, n) : nullptr;
    events.mark("upload");
    float l[3], h[3];
    particleBounds(m.inputPositions, n, l, h, *m.mem, m.stream);
    events.mark("bounds");
    lo = Vec3f(l[0], l[1], l[2]);
    hi = Vec3f(h[0], h[1], h[2]);
    m.collect(events);
}

LeafBlocks NarrowBandPipeline::run(const PipelineSettings& s)
{
    Impl& m = *mImpl;
    if (!m.inputPositions) throw Error("NarrowBandPipeline::run: upload() first");
    StageEvents events(m.stream);
    DeviceCells& cells = m.cells;
    cells.cellSize = s.cellSize;
    for (int a = 0; a < 3; ++a)
        cells.origin[a] = s.cellOrigin[a], cells.dims[a] = int(s.cellDims[a]);
    sortIntoCells(cells, m.inputPositions, m.inputRadii, m.count, *m.mem, m.stream, events);
    m.mem->release(m.inputPositions);
    if (m.inputRadii) m.mem->release(m.inputRadii);
    m.inputPositions = nullptr, m.inputRadii = nullptr;

    ClassifySettings cs;
    cs.h2 = s.h2;
    cs.smoothingLength = s.smoothingLength;
    cs.uniformVolume = s.uniformVolume;
    cs.rule.poly6 = s.poly6;
    cs.rule.gradientScale = s.gradientScale;
    cs.rule.splashNeighbours = s.splashNeighbours, cs.rule.surfaceNeighbours = s.surfaceNeighbours;
    cs.rule.colorFieldThreshold = s.colorFieldThreshold,
    cs.rule.colorGradientThreshold = s.colorGradientThreshold;
    uint8_t* classes = m.mem->alloc<uint8_t>(m.count);
    unsigned long long counts[4];
    classifyParticles(cells, cs, classes, counts, *m.mem, m.stream);
    m.counts.interior = counts[classify::Interior], m.counts.surface = counts[classify::Surface];
    m.counts.splash = counts[classify::Splash], m.counts.isolated = counts[classify::Isolated];
    events.mark("classify");
    if (s.beforeBand) s.beforeBand(m.counts);

    BandSettings bs;
    bs.width = s.bandWidth;
    bs.invDx = 1 / s.field.voxelSize;
    bs.isolatedSeeds = s.keepIsolated;
    const DeviceLeaves leaves = markBand(cells, classes, bs, *m.mem, m.stream);
    events.mark("band");
    // Isolated particles take no part in the field unless kept.
    takeIsolated(cells, classes, m.counts.isolated, !s.keepIsolated, m.isolated, *m.mem, m.stream);
    std::sort(m.isolated.begin(), m.isolated.end());
    m.mem->release(classes);

    m.voxelSize = s.field.voxelSize;
    m.constants = fieldConstants(s.field, cells.radii != nullptr);
    events.mark("isolated");
    size_t activeCount = 0;
    uint32_t* offsets = activeOffsets(leaves.masks, leaves.count, activeCount, *m.mem, m.stream);
    float* values = m.mem->alloc<float>(activeCount);
    gatherLeaves(cells, leaves.origins, leaves.masks, leaves.count, m.voxelSize, m.constants,
                 values, *m.mem, m.stream, offsets);
    events.mark("gather");

    LeafBlocks out;
    out.origins.resize(3 * leaves.count);
    out.masks.resize(8 * leaves.count);
    out.values.resize(activeCount);
    if (leaves.count) {
        FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(out.origins.data(), leaves.origins,
                                             out.origins.size() * sizeof(int32_t),
                                             cudaMemcpyDeviceToHost, m.stream));
        FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(out.masks.data(), leaves.masks,
                                             out.masks.size() * sizeof(uint64_t),
                                             cudaMemcpyDeviceToHost, m.stream));
        FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(out.values.data(), values,
                                             out.values.size() * sizeof(float),
                                             cudaMemcpyDeviceToHost, m.stream));
    }
    events.mark("download");
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(m.stream));
    m.mem->release(values);
    m.mem->release(offsets);
    m.mem->release(leaves.origins);
    m.mem->release(leaves.masks);
    m.collect(events);
    m.ran = true;
    return out;
}

const ClassCounts& NarrowBandPipeline::classCounts() const
{
    return mImpl->counts;
}
const std::vector<uint32_t>& NarrowBandPipeline::isolatedParticles() const
{
    return mImpl->isolated;
}

std::vector<float> NarrowBandPipeline::evaluate(const int32_t* origins, const uint64_t* masks,
                                                size_t leafCount)
{
    Impl& m = *mImpl;
    if (!m.ran) throw Error("NarrowBandPipeline::evaluate: run() first");
    std::vector<float> out;
    if (leafCount == 0) return out;
    StageEvents events(m.stream);
    const int32_t* o = m.mem->upload(origins, 3 * leafCount);
    const unsigned long long* k =
        m.mem->upload(reinterpret_cast<const unsigned long long*>(masks), 8 * leafCount);
    size_t active = 0;
    uint32_t* offsets = activeOffsets(k, leafCount, active, *m.mem, m.stream);
    out.resize(active);
    float* values = m.mem->alloc<float>(active);
    gatherLeaves(m.cells, o, k, leafCount, m.voxelSize, m.constants, values, *m.mem, m.stream,
                 offsets);
    FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(out.data(), values, out.size() * sizeof(float),
                                         cudaMemcpyDeviceToHost, m.stream));
    events.mark("completion gather");
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(m.stream));
    for (const void* scratch :
         {(const void*)o, (const void*)k, (const void*)offsets, (const void*)values})
        m.mem->release(scratch);
    m.collect(events);
    return out;
}

const std::vector<std::pair<std::string, double>>& NarrowBandPipeline::stageMs() const
{
    return mImpl->stages;
}
size_t NarrowBandPipeline::peakBytes() const
{
    return mImpl->mem->peakBytes();
}

} // namespace cuda
} // namespace fluidsurf
