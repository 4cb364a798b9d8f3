// GatherField.cu - the SSP07 / ZB05 gather on the GPU, one block per VDB leaf (see
// facade/FieldGather.h). The finish from sums to phi is lib/src/field/FieldMath.h, the same code
// the CPU runs. Deterministic: every run sums each voxel's particles in the same order.
#include "facade/FieldGather.h"

#include "LeafCells.cuh"
#include "Stages.cuh"

#include "field/GatherLayout.h"

#include <string>

namespace fluidsurf {
namespace cuda {

namespace {

// The CPU's gather (lib/src/field/GatherField.cc), pick for pick: each leaf gathers the particles
// of GatherLayout::box in cell order, sorts them stably by (z-slab, x-column, y-column), and each
// active voxel adds, in that order, the particles of its window's slabs and its row's x-columns
// whose (x, y) lie within R of its row's line (ex^2 + ey^2 < R^2 in float, unfused), the k-th of
// them on lane k % 8, with the CPU's fused multiply-adds (wideSums); the lanes are added in pairs
// and FieldMath's fieldValue finishes. So phi has the CPU's bits where the CPU sums on 8 lanes
// (field::fieldLanes(): AVX2 and FMA), and the meshes made from it are the CPU's, post-processing
// included. The file is built with --fmad=false: nothing else is fused.
constexpr int kThreads = kLeafThreads; // a block a leaf; 8 threads a voxel, one for each lane
constexpr int kGroups = kThreads / 8;

using field::GatherLayout;

struct Params
{
    DeviceCells cells;
    const int32_t* leafOrigins;
    const unsigned long long* leafActive;
    GatherLayout layout;
    float R2, invR2; // the row test's R^2 and the sums' 1 / R^2, as the CPU rounds them
    field::FieldConstants constants;
    float* out;
    const uint32_t* compactOffsets; // non-null: out holds only the active voxels (see Stages.cuh)
    const unsigned long long* candidateOffsets; // per leaf of the batch: where its particles go
    float4* gathered;                           // the leaves' particles in cell order (x, y, z, r)
    uint32_t* bucketOf;                         //   and each one's (slab, x-column, y-column)
    float4* sorted;                             // the same sorted by bucket, stably
    uint32_t* counts;                           // countKernel: particles per leaf
    size_t leafBase;                            // the batch's first leaf
};

/// A leaf's gather box in world units, from its active bits (GatherLayout::box); false when none
/// is active.
__device__ bool leafBox(const Params& p, size_t leaf, double o[3], double lo[3], double hi[3])
{
    int first[3], last[3];
    if (!activeVoxelBounds(p.leafActive + 8 * leaf, first, last)) return false;
    const GatherLayout& g = p.layout;
    for (int a = 0; a < 3; ++a)
        o[a] = p.leafOrigins[3 * leaf + a] * g.dx;
    g.box(first, last, lo, hi);
    return true;
}

/// Leaf-local coordinates of particle i (the CPU's: the difference in double), and whether it
/// lies inside the open box (lo, hi).
__device__ bool localOf(const Params& p, uint32_t i, const double o[3], const double lo[3],
                        const double hi[3], double l[3])
{
    const float3 x = p.cells.positions[i];
    l[0] = double(x.x) - o[0], l[1] = double(x.y) - o[1], l[2] = double(x.z) - o[2];
    return l[0] > lo[0] && l[0] < hi[0] && l[1] > lo[1] && l[1] < hi[1] && l[2] > lo[2] &&
           l[2] < hi[2];
}

struct Shared
{
    uint32_t cellBegin[kCellChunk], cellPrefix[kCellChunk + 1];
    int warpFound[kThreads / 32];
    uint32_t cellsInChunk;
    uint32_t total; // particles gathered so far
    int activeCount;
    unsigned short active[512];
};

/// How many particles each leaf gathers (the size of its part of the scratch arrays).
__global__ void __launch_bounds__(kThreads) countKernel(Params p)
{
    __shared__ Shared sh;
    const size_t leaf = p.leafBase + blockIdx.x;
    double o[3], lo[3], hi[3];
    if (!leafBox(p, leaf, o, lo, hi)) {
        if (threadIdx.x == 0) p.counts[blockIdx.x] = 0;
        return;
    }
    if (threadIdx.x == 0) sh.total = 0;
    forEachCellChunk(p.cells, o, lo, hi, sh.cellBegin, sh.cellPrefix, sh.warpFound, sh.cellsInChunk,
                     [&](const uint32_t* begin, const uint32_t* prefix, int cells) {
                         uint32_t n = 0;
                         double l[3];
                         for (uint32_t f = threadIdx.x; f < prefix[cells]; f += kThreads)
                             n += localOf(p, particleAt(begin, prefix, cells, f), o, lo, hi, l);
                         atomicAdd(&sh.total, n);
                     });
    if (threadIdx.x == 0) p.counts[blockIdx.x] = sh.total;
}

struct Lanes
{
    float w = 0, d0 = 0, d1 = 0, d2 = 0, r = 0, g0 = 0, g1 = 0, g2 = 0, m0 = 0, m1 = 0, m2 = 0,
          m3 = 0, m4 = 0, m5 = 0;
};

/// One particle on one lane: wideSums' steps (GatherField.cc), fused where it fuses.
__device__ __forceinline__ void addParticle(Lanes& a, float4 q, float vx, float vy, float vz,
                                            float invR2, bool ssp07, bool radii)
{
    const float ex = __fsub_rn(q.x, vx), ey = __fsub_rn(q.y, vy), ez = __fsub_rn(q.z, vz);
    const float d2 = __fmaf_rn(ez, ez, __fmaf_rn(ex, ex, __fmul_rn(ey, ey)));
    const float t = __fmaf_rn(-d2, invR2, 1.f);
    // Particles at t <= 1e-6 add exact zeros on the CPU (to sums that are never -0): left out.
    if (!(t > 1e-6f)) return;
    const float t2 = __fmul_rn(t, t), wt = __fmul_rn(t2, t);
    a.w = __fadd_rn(a.w, wt);
    a.d0 = __fmaf_rn(wt, ex, a.d0), a.d1 = __fmaf_rn(wt, ey, a.d1), a.d2 = __fmaf_rn(wt, ez, a.d2);
    if (radii) a.r = __fmaf_rn(wt, q.w, a.r);
    if (ssp07) {
        const float gx = __fmul_rn(t2, ex), gy = __fmul_rn(t2, ey), gz = __fmul_rn(t2, ez);
        a.g0 = __fadd_rn(a.g0, gx), a.g1 = __fadd_rn(a.g1, gy), a.g2 = __fadd_rn(a.g2, gz);
        a.m0 = __fmaf_rn(gx, ex, a.m0), a.m1 = __fmaf_rn(gx, ey, a.m1);
        a.m2 = __fmaf_rn(gx, ez, a.m2), a.m3 = __fmaf_rn(gy, ey, a.m3);
        a.m4 = __fmaf_rn(gy, ez, a.m4), a.m5 = __fmaf_rn(gz, ez, a.m5);
    }
}

/// The 8 lanes of a group added as the CPU adds a register's lanes: ((l0 + l1) + (l2 + l3)) +
/// ((l4 + l5) + (l6 + l7)); lane 0 of the group gets it.
__device__ __forceinline__ float laneSum(float v, unsigned group)
{
    v = __fadd_rn(v, __shfl_xor_sync(group, v, 1));
    v = __fadd_rn(v, __shfl_xor_sync(group, v, 2));
    return __fadd_rn(v, __shfl_xor_sync(group, v, 4));
}

/// One leaf: its particles gathered (cell order) and sorted by bucket into the scratch arrays,
/// then every active voxel summed by a group of 8 threads. Dynamic shared memory: one counter a
/// bucket (slabCount * binCount^2, + 1).
__global__ void __launch_bounds__(kThreads) fieldKernel(Params p)
{
    __shared__ Shared sh;
    extern __shared__ uint32_t bucketEnd[];
    const size_t leaf = p.leafBase + blockIdx.x;
    const GatherLayout& g = p.layout;
    const int B = g.binCount(), buckets = g.slabCount() * B * B;
    const unsigned long long base = p.candidateOffsets[blockIdx.x];
    float4* gathered = p.gathered + base;
    uint32_t* bucketOf = p.bucketOf + base;
    float4* sorted = p.sorted + base;
    double o[3], lo[3], hi[3];
    const bool any = leafBox(p, leaf, o, lo, hi);

    // 1. Gathered in cell order (each tile of the chunk compacted in order), bucket counts.
    for (int b = threadIdx.x; b < buckets; b += kThreads)
        bucketEnd[b] = 0;
    if (threadIdx.x == 0) sh.total = 0, sh.activeCount = 0;
    __syncthreads();
    if (any)
        forEachCellChunk(
            p.cells, o, lo, hi, sh.cellBegin, sh.cellPrefix, sh.warpFound, sh.cellsInChunk,
            [&](const uint32_t* begin, const uint32_t* prefix, int cells) {
                const uint32_t n = prefix[cells];
                for (uint32_t tile = 0; tile < n; tile += kThreads) {
                    const uint32_t f = tile + threadIdx.x;
                    double l[3];
                    uint32_t i = 0;
                    bool in = false;
                    if (f < n) {
                        i = particleAt(begin, prefix, cells, f);
                        in = localOf(p, i, o, lo, hi, l);
                    }
                    const uint32_t at = keptSlot(in, sh.warpFound, sh.total);
                    if (in) {
                        const float lz = float(l[2]);
                        const uint32_t bucket =
                            uint32_t((g.slabOf(lz) * B + g.binOf(l[0])) * B + g.binOf(l[1]));
                        gathered[at] = make_float4(float(l[0]), float(l[1]), lz,
                                                   p.cells.radii ? p.cells.radii[i] : 0.f);
                        bucketOf[at] = bucket;
                        atomicAdd(&bucketEnd[bucket], 1u);
                    }
                }
            });
    __syncthreads();
    const uint32_t total = sh.total;

    // 2. Bucket starts (exclusive sums: each thread a run of buckets, then the runs' totals).
    {
        const int per = (buckets + kThreads - 1) / kThreads;
        const int b0 = min(buckets, int(threadIdx.x) * per), b1 = min(buckets, b0 + per);
        uint32_t run = 0;
        for (int b = b0; b < b1; ++b)
            run += bucketEnd[b];
        __shared__ uint32_t runStart[kThreads];
        runStart[threadIdx.x] = run;
        __syncthreads();
        if (threadIdx.x == 0)
            for (int t = 0, sum = 0; t < kThreads; ++t) {
                const uint32_t r = runStart[t];
                runStart[t] = sum, sum += r;
            }
        __syncthreads();
        uint32_t at = runStart[threadIdx.x];
        for (int b = b0; b < b1; ++b) {
            const uint32_t c = bucketEnd[b];
            bucketEnd[b] = at, at += c;
        }
    }
    __syncthreads();

    // 3. Sorted stably by one warp, 32 particles at a time in gather order: those of one bucket
    // go to its cursor in lane order. The cursors end as the buckets' ends.
    if (threadIdx.x < 32) {
        const unsigned lane = threadIdx.x;
        for (uint32_t at = 0; at < total; at += 32) {
            const bool valid = at + lane < total;
            const uint32_t bucket = valid ? bucketOf[at + lane] : 0xffffffffu;
            const unsigned peers = __match_any_sync(0xffffffffu, bucket);
            const int leader = __ffs(peers) - 1;
            uint32_t start = 0;
            if (valid && int(lane) == leader)
                start = bucketEnd[bucket], bucketEnd[bucket] += __popc(peers);
            start = __shfl_sync(0xffffffffu, start, leader);
            if (valid) sorted[start + __popc(peers & ((1u << lane) - 1u))] = gathered[at + lane];
        }
    }
    // The active voxels, in any order (each is summed alone).
    for (int v = threadIdx.x; v < 512; v += kThreads) {
        const bool on = (p.leafActive[8 * leaf + (v >> 6)] >> (v & 63)) & 1ull;
        if (on)
            sh.active[atomicAdd(&sh.activeCount, 1)] = (unsigned short)(v);
        else if (!p.compactOffsets)
            p.out[leaf * 512 + v] = p.constants.background;
    }
    __syncthreads();

    // 4. The sums: group `group` of 8 threads takes every kGroups-th active voxel.
    const int lane8 = threadIdx.x & 7;
    const unsigned groupMask = 0xffu << (threadIdx.x & 24);
    const bool radii = p.cells.radii != nullptr, ssp07 = p.constants.ssp07;
    for (int a = threadIdx.x >> 3; a < sh.activeCount; a += kGroups) {
        const int v = sh.active[a], i = v >> 6, j = (v >> 3) & 7, k = v & 7;
        const double rowX = i * g.dx;
        const float vx = float(rowX), vy = float(j * g.dx), vz = float(k * g.dx);
        const int xlo = g.binOf(rowX - g.R), xhi = g.binOf(rowX + g.R);
        Lanes acc;
        unsigned picked = 0; // row-picked particles of the window so far
        for (int z = k; z < k + g.window; ++z) {
            // sections (z, xlo) to (z, xhi): buckets (z B + x) B + y, one run
            const int first = (z * B + xlo) * B, end = (z * B + xhi + 1) * B;
            const uint32_t e = bucketEnd[end - 1];
            for (uint32_t s = first ? bucketEnd[first - 1] : 0; s < e; s += 8) {
                const uint32_t at = s + lane8;
                float4 q = make_float4(0.f, 0.f, 0.f, 0.f);
                bool pick = false;
                if (at < e) {
                    q = sorted[at];
                    const float ex = __fsub_rn(q.x, vx), ey = __fsub_rn(q.y, vy);
                    pick = __fadd_rn(__fmul_rn(ex, ex), __fmul_rn(ey, ey)) < p.R2;
                }
                const unsigned bits =
                    (__ballot_sync(groupMask, pick) >> (threadIdx.x & 24)) & 0xffu;
                // this lane's particle, if any: the ((lane - picked) mod 8)-th picked
                unsigned left = bits;
                for (unsigned n = (lane8 - picked) & 7u; n > 0 && left; --n)
                    left &= left - 1;
                const int from = left ? __ffs(left) - 1 : lane8;
                const int src = (threadIdx.x & 31 & ~7) + from;
                float4 mine;
                mine.x = __shfl_sync(groupMask, q.x, src);
                mine.y = __shfl_sync(groupMask, q.y, src);
                mine.z = __shfl_sync(groupMask, q.z, src);
                mine.w = __shfl_sync(groupMask, q.w, src);
                if (left) addParticle(acc, mine, vx, vy, vz, p.invR2, ssp07, radii);
                picked += __popc(bits);
            }
        }
        field::FieldSums sums;
        sums.w = laneSum(acc.w, groupMask), sums.r = laneSum(acc.r, groupMask);
        sums.d[0] = laneSum(acc.d0, groupMask), sums.d[1] = laneSum(acc.d1, groupMask);
        sums.d[2] = laneSum(acc.d2, groupMask);
        sums.g[0] = laneSum(acc.g0, groupMask), sums.g[1] = laneSum(acc.g1, groupMask);
        sums.g[2] = laneSum(acc.g2, groupMask);
        sums.m[0] = laneSum(acc.m0, groupMask), sums.m[1] = laneSum(acc.m1, groupMask);
        sums.m[2] = laneSum(acc.m2, groupMask), sums.m[3] = laneSum(acc.m3, groupMask);
        sums.m[4] = laneSum(acc.m4, groupMask), sums.m[5] = laneSum(acc.m5, groupMask);
        if (lane8 == 0) {
            const float value = field::fieldValue(sums, p.constants);
            if (!p.compactOffsets) {
                p.out[leaf * 512 + v] = value;
            } else {
                // Rank of the voxel among the leaf's active voxels: the bits below it.
                const int word = v >> 6;
                uint32_t rank = __popcll(p.leafActive[8 * leaf + word] & ((1ull << (v & 63)) - 1));
                for (int w = 0; w < word; ++w)
                    rank += __popcll(p.leafActive[8 * leaf + w]);
                p.out[p.compactOffsets[leaf] + rank] = value;
            }
        }
    }
}

/// Scratch particles a batch of leaves may take at once (36 bytes each: gathered, its bucket,
/// sorted: 36 MiB); a leaf with more runs alone. 1M particles are some 6,000 leaves, enough
/// blocks to fill the device.
constexpr unsigned long long kBatchParticles = 1ull << 20;

} // namespace

field::FieldConstants fieldConstants(const FieldSettings& s, bool perParticleRadii)
{
    field::FieldConstants c;
    c.influenceRadius = s.influenceRadius;
    c.radius = s.radius;
    c.radiusScale = s.radiusScale;
    c.perParticleRadii = perParticleRadii;
    c.ssp07 = s.ssp07;
    c.density = s.density, c.isoLevel = s.isoLevel;
    c.tLow = s.tLow, c.tHigh = s.tHigh;
    c.background = s.background;
    return c;
}

size_t gatherSharedBytes(double voxelSize, double influenceRadius)
{
    const GatherLayout g = GatherLayout::of(voxelSize, influenceRadius);
    return size_t(g.slabCount()) * g.binCount() * g.binCount() * sizeof(uint32_t);
}

bool gatherFits(double voxelSize, double influenceRadius)
{
    if (!(voxelSize > 0 && influenceRadius > 0 && influenceRadius / voxelSize < 1e6)) return false;
    int device = 0, optin = 0;
    if (cudaGetDevice(&device) != cudaSuccess ||
        cudaDeviceGetAttribute(&optin, cudaDevAttrMaxSharedMemoryPerBlockOptin, device) !=
            cudaSuccess)
        return false;
    return gatherSharedBytes(voxelSize, influenceRadius) + sizeof(Shared) + 1024 <= size_t(optin);
}

void gatherLeaves(const DeviceCells& cells, const int32_t* origins, const unsigned long long* masks,
                  size_t leafCount, double voxelSize, const field::FieldConstants& constants,
                  float* out, DeviceMemory& mem, cudaStream_t stream,
                  const uint32_t* compactOffsets)
{
    if (leafCount == 0) return;
    const double R = constants.influenceRadius;
    if (!gatherFits(voxelSize, R))
        throw Error("gatherField: the support radius spans too many voxels for the device's "
                    "shared memory (R / voxel size " +
                    std::to_string(R / voxelSize) + ")");
    Params p{};
    p.cells = cells;
    p.leafOrigins = origins;
    p.leafActive = masks;
    p.layout = GatherLayout::of(voxelSize, R);
    p.R2 = float(R * R), p.invR2 = float(1 / (R * R));
    p.constants = constants;
    p.out = out;
    p.compactOffsets = compactOffsets;
    const size_t shared = gatherSharedBytes(voxelSize, R);
    if (shared > 48 * 1024)
        FLUIDSURF_CUDA_CHECK(cudaFuncSetAttribute(
            fieldKernel, cudaFuncAttributeMaxDynamicSharedMemorySize, int(shared)));

    // How many particles each leaf gathers, then the leaves in batches whose scratch fits.
    p.counts = mem.alloc<uint32_t>(leafCount);
    countKernel<<<unsigned(leafCount), kThreads, 0, stream>>>(p);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    forEachLeafBatch(p.counts, leafCount, kBatchParticles, stream,
                     [&](size_t begin, size_t end, const std::vector<unsigned long long>& offsets,
                         unsigned long long total) {
                         p.leafBase = begin;
                         p.candidateOffsets = mem.upload(offsets.data(), offsets.size());
                         p.gathered = mem.alloc<float4>(total), p.sorted = mem.alloc<float4>(total);
                         p.bucketOf = mem.alloc<uint32_t>(total);
                         fieldKernel<<<unsigned(end - begin), kThreads, shared, stream>>>(p);
                         FLUIDSURF_CUDA_CHECK(cudaGetLastError());
                         for (const void* scratch :
                              {(const void*)p.candidateOffsets, (const void*)p.gathered,
                               (const void*)p.sorted, (const void*)p.bucketOf})
                             mem.release(scratch);
                     });
    mem.release(p.counts);
}

DeviceCells uploadCells(const GatherInput& in, DeviceMemory& mem)
{
    static_assert(sizeof(Vec3f) == sizeof(float3), "Vec3f must be three packed floats");
    DeviceCells cells;
    cells.count = in.particleCount;
    cells.positions = mem.upload(reinterpret_cast<const float3*>(in.positions), in.particleCount);
    cells.radii = in.radii ? mem.upload(in.radii, in.particleCount) : nullptr;
    cells.starts = mem.upload(in.cellStarts, in.cellCount + 1);
    cells.tableKeys =
        mem.upload(reinterpret_cast<const unsigned long long*>(in.tableKeys), in.tableSize);
    cells.tableCells = mem.upload(in.tableCells, in.tableSize);
    cells.tableMask = in.tableSize - 1;
    cells.cellCount = in.cellCount;
    cells.cellSize = in.cellSize;
    for (int a = 0; a < 3; ++a)
        cells.origin[a] = in.cellOrigin[a], cells.dims[a] = int(in.cellDims[a]);
    return cells;
}

std::vector<float> gatherField(const GatherInput& in, GatherTimes* times, void* streamPtr)
{
    std::vector<float> out;
    if (in.leafCount == 0) return out;
    if (!(in.cellSize > 0 && in.field.voxelSize > 0 && in.field.influenceRadius > 0))
        throw Error("gatherField: invalid sizes");
    if (in.tableSize == 0 || (in.tableSize & (in.tableSize - 1)))
        throw Error("gatherField: the cell hash table size must be a power of two");
    const Stream ownStream(streamPtr);
    const cudaStream_t stream = ownStream.get();
    DeviceMemory mem(stream);
    StageEvents events(stream);
    const DeviceCells cells = uploadCells(in, mem);
    const int32_t* origins = mem.upload(in.leafOrigins, 3 * in.leafCount);
    const unsigned long long* masks =
        mem.upload(reinterpret_cast<const unsigned long long*>(in.leafActive), 8 * in.leafCount);
    const field::FieldConstants constants = fieldConstants(in.field, in.radii != nullptr);
    size_t active = 0;
    const uint32_t* offsets = activeOffsets(masks, in.leafCount, active, mem, stream);
    out.resize(active);
    float* values = mem.alloc<float>(active);
    events.mark("upload");
    gatherLeaves(cells, origins, masks, in.leafCount, in.field.voxelSize, constants, values, mem,
                 stream, offsets);
    events.mark("gather kernel");
    FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(out.data(), values, out.size() * sizeof(float),
                                         cudaMemcpyDeviceToHost, stream));
    events.mark("download");
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
    if (times) {
        const auto stages = events.stages();
        times->uploadMs = stages[0].second;
        times->kernelMs = stages[1].second;
        times->downloadMs = stages[2].second;
        times->deviceBytes = mem.peakBytes();
    }
    return out;
}

} // namespace cuda
} // namespace fluidsurf
