// AnisotropicGather.cu - the ssp07-aniso and yt10 fields on the GPU (facade/FieldGather.h), one
// block per VDB leaf, with the CPU's bits (lib/src/field/AnisotropicField.h): each voxel adds its
// kernels one after another in the cell index's order, with AnisotropicSums.h's operations (this
// file is built with --fmad=false: nothing else is fused), and FieldMath's fieldValue finishes. The
// CPU tests kernels per block of voxels, this file per voxel; a kernel that does not reach a voxel
// adds exact zeros on the CPU and is left out here, so both sum the same terms in the same order.
#include "facade/FieldGather.h"

#include "LeafCells.cuh"
#include "Stages.cuh"

#include "field/AnisotropicSums.h"

namespace fluidsurf {
namespace cuda {

namespace {

constexpr int kThreads = kLeafThreads; // a thread a voxel, a round for each 256 active voxels
constexpr int kTile = 256;             // kernels staged in shared memory at a time

struct Params
{
    DeviceCells cells;   ///< the kernels' centres (and radii) in cell order
    const float* a;      ///< 6 a kernel: A' = R^2 G^2
    const float* extent; ///< 3 a kernel: the box's half extents
    const float* weight; ///< yt10: 1 a kernel, in the radius slot (else null)
    double reach, dx;
    const int32_t* leafOrigins;
    const unsigned long long* leafActive;
    float invR2;
    field::FieldConstants constants;
    float* out;                        ///< the active voxels' phi, leaf after leaf
    const uint32_t* activeBefore;      ///< per leaf: the active voxels of the leaves before it
    const unsigned long long* offsets; ///< per leaf of the batch: where its kernels go
    float4* kernels;                   ///< 3 a kernel: (c, r), (a0..a3), (a4, a5, 0, 0)
    uint32_t* counts;                  ///< countKernel: kernels per leaf
    size_t leafBase;
};

/// The leaf's origin and its active voxels' box in world units (AnisotropicField.cc: the same
/// doubles); false when none is active.
__device__ bool activeBox(const Params& p, size_t leaf, double o[3], double lo[3], double hi[3])
{
    int first[3], last[3];
    if (!activeVoxelBounds(p.leafActive + 8 * leaf, first, last)) return false;
    for (int a = 0; a < 3; ++a) {
        o[a] = p.leafOrigins[3 * leaf + a] * p.dx;
        lo[a] = o[a] + first[a] * p.dx, hi[a] = o[a] + last[a] * p.dx;
    }
    return true;
}

/// Whether kernel i's box overlaps [lo, hi] (the CPU's test, float sums against doubles).
__device__ bool overlaps(const Params& p, uint32_t i, const double lo[3], const double hi[3])
{
    const float3 c = p.cells.positions[i];
    const float x[3] = {c.x, c.y, c.z};
    bool in = true;
    for (int a = 0; a < 3; ++a) {
        const float e = p.extent[3 * size_t(i) + a];
        in &= double(__fadd_rn(x[a], e)) >= lo[a] && double(__fsub_rn(x[a], e)) <= hi[a];
    }
    return in;
}

struct Shared
{
    uint32_t cellBegin[kCellChunk], cellPrefix[kCellChunk + 1];
    int warpFound[kThreads / 32];
    uint32_t cellsInChunk;
    uint32_t total;
    int activeCount;
    unsigned short active[512];
    float4 tile[3][kTile];
};

/// The walk over the leaf's cells (its active box and the longest kernel's reach) calling
/// visit(kernel) for each kernel whose box overlaps the active box, in cell order.
template <typename Visit>
__device__ void forEachKernel(const Params& p, Shared& sh, size_t leaf, double o[3], Visit&& visit)
{
    double lo[3], hi[3];
    if (!activeBox(p, leaf, o, lo, hi)) return;
    double cellLo[3], cellHi[3]; // relative to o, for forEachCellChunk
    for (int a = 0; a < 3; ++a)
        cellLo[a] = lo[a] - p.reach - o[a], cellHi[a] = hi[a] + p.reach - o[a];
    forEachCellChunk(p.cells, o, cellLo, cellHi, sh.cellBegin, sh.cellPrefix, sh.warpFound,
                     sh.cellsInChunk,
                     [&](const uint32_t* begin, const uint32_t* prefix, int cells) {
                         const uint32_t n = prefix[cells];
                         for (uint32_t tile = 0; tile < n; tile += kThreads) {
                             const uint32_t f = tile + threadIdx.x;
                             uint32_t i = 0;
                             bool in = false;
                             if (f < n) {
                                 i = particleAt(begin, prefix, cells, f);
                                 in = overlaps(p, i, lo, hi);
                             }
                             visit(i, in);
                         }
                     });
}

__global__ void __launch_bounds__(kThreads) countKernel(Params p)
{
    __shared__ Shared sh;
    const size_t leaf = p.leafBase + blockIdx.x;
    if (threadIdx.x == 0) sh.total = 0;
    __syncthreads();
    double o[3] = {0, 0, 0};
    forEachKernel(p, sh, leaf, o, [&](uint32_t, bool in) {
        const unsigned found = __ballot_sync(0xffffffffu, in);
        if ((threadIdx.x & 31) == 0) atomicAdd(&sh.total, unsigned(__popc(found)));
    });
    __syncthreads();
    if (threadIdx.x == 0) p.counts[blockIdx.x] = sh.total;
}

template <bool Radii>
__device__ void sumTile(field::AnisotropicAccumulator<float>& s, const Shared& sh, int n, float vx,
                        float vy, float vz, float invR2)
{
    for (int k = 0; k < n; ++k) {
        const float4 c = sh.tile[0][k], a0 = sh.tile[1][k], a1 = sh.tile[2][k];
        const float centre[3] = {c.x, c.y, c.z};
        const float a[6] = {a0.x, a0.y, a0.z, a0.w, a1.x, a1.y};
        field::addKernel<field::ScalarFloatOps, Radii>(s, centre, a, c.w, vx, vy, vz, invR2);
    }
}

/// One leaf: its kernels gathered in cell order, then each active voxel summed by one thread.
__global__ void __launch_bounds__(kThreads) fieldKernel(Params p)
{
    __shared__ Shared sh;
    const size_t leaf = p.leafBase + blockIdx.x;
    float4* kernels = p.kernels + 3 * p.offsets[blockIdx.x];
    if (threadIdx.x == 0) sh.total = 0, sh.activeCount = 0;
    __syncthreads();
    double o[3] = {0, 0, 0};
    forEachKernel(p, sh, leaf, o, [&](uint32_t i, bool in) {
        const uint32_t at = keptSlot(in, sh.warpFound, sh.total);
        if (!in) return;
        const float3 c = p.cells.positions[i];
        const float* a = p.a + 6 * size_t(i);
        kernels[3 * at] = make_float4(float(double(c.x) - o[0]), float(double(c.y) - o[1]),
                                      float(double(c.z) - o[2]),
                                      p.weight        ? p.weight[i]
                                      : p.cells.radii ? p.cells.radii[i]
                                                      : 0.f);
        kernels[3 * at + 1] = make_float4(a[0], a[1], a[2], a[3]);
        kernels[3 * at + 2] = make_float4(a[4], a[5], 0.f, 0.f);
    });
    for (int v = threadIdx.x; v < 512; v += kThreads)
        if ((p.leafActive[8 * leaf + (v >> 6)] >> (v & 63)) & 1ull)
            sh.active[atomicAdd(&sh.activeCount, 1)] = (unsigned short)(v);
    __syncthreads();
    const uint32_t total = sh.total;
    const bool radii = p.cells.radii != nullptr || p.weight != nullptr;
    for (int round = 0; round * kThreads < sh.activeCount; ++round) { // (block-uniform)
        const int slot = round * kThreads + threadIdx.x;
        const bool mine = slot < sh.activeCount;
        const int v = mine ? sh.active[slot] : 0;
        const float vx = float((v >> 6) * p.dx), vy = float(((v >> 3) & 7) * p.dx),
                    vz = float((v & 7) * p.dx);
        field::AnisotropicAccumulator<float> s;
        for (uint32_t t0 = 0; t0 < total; t0 += kTile) {
            const int n = int(min(uint32_t(kTile), total - t0));
            __syncthreads();
            for (int k = threadIdx.x; k < n; k += kThreads)
                for (int q = 0; q < 3; ++q)
                    sh.tile[q][k] = kernels[3 * (t0 + k) + q];
            __syncthreads();
            if (!mine) continue;
            if (radii)
                sumTile<true>(s, sh, n, vx, vy, vz, p.invR2);
            else
                sumTile<false>(s, sh, n, vx, vy, vz, p.invR2);
        }
        if (mine) {
            // The voxel's rank among the leaf's active voxels: the bits below it.
            const unsigned long long* words = p.leafActive + 8 * leaf;
            uint32_t rank = __popcll(words[v >> 6] & ((1ull << (v & 63)) - 1));
            for (int w = 0; w < (v >> 6); ++w)
                rank += __popcll(words[w]);
            p.out[p.activeBefore[leaf] + rank] =
                field::fieldValue(field::toSums(s.w, s.d0, s.d1, s.d2, s.r, s.g0, s.g1, s.g2, s.m0,
                                                s.m1, s.m2, s.m3, s.m4, s.m5),
                                  p.constants);
        }
    }
}

/// Kernel j's a, extent and weight from the packed entries (AnisotropicInput::fresh): the last
/// entry at or before j.
__global__ void unpackKernel(const uint32_t* fresh, const uint32_t* freshBefore, size_t n,
                             const float* a, const float* extent, const float* weight, float* aOut,
                             float* extentOut, float* weightOut)
{
    const size_t j = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (j >= n) return;
    const uint32_t bits = fresh[j >> 5] & (0xffffffffu >> (31 - (j & 31)));
    const size_t e = freshBefore[j >> 5] + __popc(bits) - 1; // (kernel 0 is always fresh)
    for (int k = 0; k < 6; ++k)
        aOut[6 * j + k] = a[6 * e + k];
    for (int k = 0; k < 3; ++k)
        extentOut[3 * j + k] = extent[3 * e + k];
    if (weight) weightOut[j] = weight[e];
}

/// Gathered kernels a batch of leaves may hold at once (48 bytes each: 48 MiB).
constexpr unsigned long long kBatchKernels = 1ull << 20;

} // namespace

struct AnisotropicGather::Impl
{
    Impl() : stream(nullptr), mem(stream.get()) {}
    Stream stream;
    DeviceMemory mem;
    Params p{};
    double kernelUploadMs = 0; ///< counted in the first evaluate()'s upload
};

AnisotropicGather::AnisotropicGather(const AnisotropicInput& in)
{
    const GatherInput& g = in.gather;
    if (!(g.cellSize > 0 && g.field.voxelSize > 0 && g.field.influenceRadius > 0 && in.reach > 0))
        throw Error("AnisotropicGather: invalid sizes");
    if (g.tableSize == 0 || (g.tableSize & (g.tableSize - 1)))
        throw Error("AnisotropicGather: the cell hash table size must be a power of two");
    mImpl = std::make_unique<Impl>();
    DeviceMemory& mem = mImpl->mem;
    StageEvents events(mImpl->stream.get());
    Params& p = mImpl->p;
    p.cells = uploadCells(g, mem);
    const size_t n = g.particleCount;
    if (!in.fresh) {
        p.a = mem.upload(in.a, 6 * n);
        p.extent = mem.upload(in.extent, 3 * n);
        p.weight = in.weight ? mem.upload(in.weight, n) : nullptr;
    } else if (n > 0) {
        if (!(in.freshCount >= 1 && in.freshCount <= n && (in.fresh[0] & 1u)))
            throw Error("AnisotropicGather: invalid packed kernels");
        const size_t m = in.freshCount, words = (n + 31) / 32;
        const uint32_t* fresh = mem.upload(in.fresh, words);
        const uint32_t* before = mem.upload(in.freshBefore, words);
        const float* a = mem.upload(in.a, 6 * m);
        const float* extent = mem.upload(in.extent, 3 * m);
        const float* weight = in.weight ? mem.upload(in.weight, m) : nullptr;
        float* aOut = mem.alloc<float>(6 * n);
        float* extentOut = mem.alloc<float>(3 * n);
        float* weightOut = weight ? mem.alloc<float>(n) : nullptr;
        unpackKernel<<<unsigned((n + 255) / 256), 256, 0, mImpl->stream.get()>>>(
            fresh, before, n, a, extent, weight, aOut, extentOut, weightOut);
        FLUIDSURF_CUDA_CHECK(cudaGetLastError());
        for (const void* packed : {(const void*)fresh, (const void*)before, (const void*)a,
                                   (const void*)extent, (const void*)weight})
            if (packed) mem.release(packed);
        p.a = aOut, p.extent = extentOut, p.weight = weightOut;
    }
    p.reach = in.reach, p.dx = g.field.voxelSize;
    const double R = g.field.influenceRadius;
    p.invR2 = float(1 / (R * R));
    p.constants = fieldConstants(g.field, g.radii != nullptr || in.weight != nullptr);
    events.mark("kernels");
    mImpl->kernelUploadMs = events.stages()[0].second;
}

AnisotropicGather::~AnisotropicGather() = default;

std::vector<float> AnisotropicGather::evaluate(const int32_t* leafOrigins,
                                               const uint64_t* leafActive, size_t leafCount,
                                               GatherTimes* times)
{
    std::vector<float> out;
    if (leafCount == 0) return out;
    const cudaStream_t stream = mImpl->stream.get();
    DeviceMemory& mem = mImpl->mem;
    StageEvents events(stream);
    Params p = mImpl->p;
    p.leafOrigins = mem.upload(leafOrigins, 3 * leafCount);
    p.leafActive =
        mem.upload(reinterpret_cast<const unsigned long long*>(leafActive), 8 * leafCount);
    size_t active = 0;
    uint32_t* activeBefore = activeOffsets(p.leafActive, leafCount, active, mem, stream);
    p.activeBefore = activeBefore;
    out.resize(active);
    p.out = mem.alloc<float>(active);
    events.mark("upload");

    // How many kernels each leaf gathers, then the leaves in batches whose scratch fits.
    p.counts = mem.alloc<uint32_t>(leafCount);
    p.leafBase = 0;
    countKernel<<<unsigned(leafCount), kThreads, 0, stream>>>(p);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    forEachLeafBatch(p.counts, leafCount, kBatchKernels, stream,
                     [&](size_t begin, size_t end, const std::vector<unsigned long long>& offsets,
                         unsigned long long total) {
                         p.leafBase = begin;
                         p.offsets = mem.upload(offsets.data(), offsets.size());
                         p.kernels = mem.alloc<float4>(3 * total + 1);
                         fieldKernel<<<unsigned(end - begin), kThreads, 0, stream>>>(p);
                         FLUIDSURF_CUDA_CHECK(cudaGetLastError());
                         mem.release(p.offsets), mem.release(p.kernels);
                     });
    events.mark("gather kernel");
    FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(out.data(), p.out, out.size() * sizeof(float),
                                         cudaMemcpyDeviceToHost, stream));
    events.mark("download");
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
    for (const void* scratch :
         {(const void*)p.leafOrigins, (const void*)p.leafActive, (const void*)p.activeBefore,
          (const void*)p.out, (const void*)p.counts})
        mem.release(scratch);
    if (times) {
        const auto stages = events.stages();
        times->uploadMs = stages[0].second + mImpl->kernelUploadMs;
        times->kernelMs = stages[1].second;
        times->downloadMs = stages[2].second;
        times->deviceBytes = mem.peakBytes();
    }
    mImpl->kernelUploadMs = 0;
    return out;
}

} // namespace cuda
} // namespace fluidsurf
