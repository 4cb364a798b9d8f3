// NarrowBand.cu - narrow-band topology on the device (the twin of
// lib/src/narrowband/NarrowBand.cc): every voxel within +-width per axis of a seed particle, as
// VDB-style leaf blocks.
//
// Each seed's voxel box touches a few 8^3 leaves. The (seed, leaf) keys are counted, written,
// radix-sorted and de-duplicated (CUB) into the sorted leaf list; then each seed ORs the part of
// its box inside each of its leaves into that leaf's 8 mask words: the box's (y, z) rectangle is
// one 64-bit pattern, the same for every x row. Compiled without FMA contraction so the voxel
// ranges round exactly as on the CPU.
#include "LeafKeys.cuh"
#include "Stages.cuh"

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>
#include <cub/device/device_select.cuh>

namespace fluidsurf {
namespace cuda {

namespace {

constexpr int kThreads = 256;

unsigned blocksFor(size_t n)
{
    return unsigned((n + kThreads - 1) / kThreads);
}

__device__ __forceinline__ bool isSeed(uint8_t cls, bool isolatedSeeds)
{
    return cls == classify::Surface || cls == classify::Splash ||
           (isolatedSeeds && cls == classify::Isolated);
}

/// The seed's voxel box, inclusive (NarrowBand.cc: within the width, up to 1e-6 voxel).
__device__ __forceinline__ void voxelBox(const float3& p, const BandSettings& s, int lo[3],
                                         int hi[3])
{
    const float v[3] = {p.x, p.y, p.z};
    for (int a = 0; a < 3; ++a) {
        lo[a] = int(ceil((double(v[a]) - s.width) * s.invDx - 1e-6));
        hi[a] = int(floor((double(v[a]) + s.width) * s.invDx + 1e-6));
    }
}

__device__ __forceinline__ unsigned long long leafKey(int lx, int ly, int lz)
{
    return (unsigned long long)(lx + kLeafBias) << 42 | (unsigned long long)(ly + kLeafBias) << 21 |
           (unsigned long long)(lz + kLeafBias);
}

__global__ void countLeavesKernel(DeviceCells c, const uint8_t* __restrict__ classes,
                                  BandSettings s, uint32_t* __restrict__ counts)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= c.count) return;
    uint32_t n = 0;
    if (isSeed(classes[i], s.isolatedSeeds)) {
        int lo[3], hi[3];
        voxelBox(c.positions[i], s, lo, hi);
        n = 1;
        for (int a = 0; a < 3; ++a)
            n *= uint32_t((hi[a] >> 3) - (lo[a] >> 3) + 1);
    }
    counts[i] = n;
}

__global__ void writeLeavesKernel(DeviceCells c, const uint8_t* __restrict__ classes,
                                  BandSettings s, const uint32_t* __restrict__ offsets,
                                  unsigned long long* __restrict__ keys)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= c.count || !isSeed(classes[i], s.isolatedSeeds)) return;
    int lo[3], hi[3];
    voxelBox(c.positions[i], s, lo, hi);
    uint32_t k = offsets[i];
    for (int lx = lo[0] >> 3; lx <= hi[0] >> 3; ++lx)
        for (int ly = lo[1] >> 3; ly <= hi[1] >> 3; ++ly)
            for (int lz = lo[2] >> 3; lz <= hi[2] >> 3; ++lz)
                keys[k++] = leafKey(lx, ly, lz);
}

__global__ void maskKernel(DeviceCells c, const uint8_t* __restrict__ classes, BandSettings s,
                           const unsigned long long* __restrict__ leafKeys, size_t leafCount,
                           unsigned long long* masks)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= c.count || !isSeed(classes[i], s.isolatedSeeds)) return;
    int lo[3], hi[3];
    voxelBox(c.positions[i], s, lo, hi);
    for (int lx = lo[0] >> 3; lx <= hi[0] >> 3; ++lx)
        for (int ly = lo[1] >> 3; ly <= hi[1] >> 3; ++ly)
            for (int lz = lo[2] >> 3; lz <= hi[2] >> 3; ++lz) {
                const long long leaf = findLeaf(leafKeys, leafCount, leafKey(lx, ly, lz));
                if (leaf < 0) continue; // cannot happen: every key was written
                const int x0 = max(lo[0] - 8 * lx, 0), x1 = min(hi[0] - 8 * lx, 7);
                const int y0 = max(lo[1] - 8 * ly, 0), y1 = min(hi[1] - 8 * ly, 7);
                const int z0 = max(lo[2] - 8 * lz, 0), z1 = min(hi[2] - 8 * lz, 7);
                const unsigned long long zbits = ((1ull << (z1 - z0 + 1)) - 1) << z0;
                unsigned long long plane = 0;
                for (int y = y0; y <= y1; ++y)
                    plane |= zbits << (8 * y);
                for (int x = x0; x <= x1; ++x)
                    atomicOr(&masks[8 * size_t(leaf) + x], plane);
            }
}

__global__ void originKernel(const unsigned long long* __restrict__ keys, size_t count,
                             int32_t* __restrict__ origins)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= count) return;
    const unsigned long long k = keys[i];
    const unsigned long long field = (1ull << 21) - 1;
    origins[3 * i] = 8 * (int(k >> 42 & field) - kLeafBias);
    origins[3 * i + 1] = 8 * (int(k >> 21 & field) - kLeafBias);
    origins[3 * i + 2] = 8 * (int(k & field) - kLeafBias);
}

__global__ void popcountKernel(const unsigned long long* __restrict__ masks, size_t count,
                               uint32_t* __restrict__ out)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i > count) return;
    uint32_t n = 0;
    if (i < count)
        for (int w = 0; w < 8; ++w)
            n += __popcll(masks[8 * i + w]);
    out[i] = n;
}

/// Exclusive prefix sums of counts[0..n] (counts[n] must be 0) into a new array; the total (its
/// last entry) comes back to the host. counts is freed.
uint32_t* scanCounts(uint32_t* counts, size_t n, size_t& total, DeviceMemory& mem,
                     cudaStream_t stream)
{
    uint32_t* offsets = mem.alloc<uint32_t>(n + 1);
    runCub(mem, [&](void* scratch, size_t& bytes) {
        return cub::DeviceScan::ExclusiveSum(scratch, bytes, counts, offsets, n + 1, stream);
    });
    mem.release(counts);
    uint32_t last = 0;
    FLUIDSURF_CUDA_CHECK(
        cudaMemcpyAsync(&last, offsets + n, sizeof(uint32_t), cudaMemcpyDeviceToHost, stream));
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
    total = last;
    return offsets;
}

} // namespace

uint32_t* activeOffsets(const unsigned long long* masks, size_t leafCount, size_t& total,
                        DeviceMemory& mem, cudaStream_t stream)
{
    uint32_t* counts = mem.alloc<uint32_t>(leafCount + 1);
    popcountKernel<<<blocksFor(leafCount + 1), kThreads, 0, stream>>>(masks, leafCount, counts);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    return scanCounts(counts, leafCount, total, mem, stream);
}

DeviceLeaves markBand(const DeviceCells& cells, const uint8_t* classes, const BandSettings& s,
                      DeviceMemory& mem, cudaStream_t stream)
{
    DeviceLeaves out;
    const size_t n = cells.count;
    if (n == 0) return out;
    // (seed, leaf) pairs: count, offsets (the extra last entry is the total), keys.
    uint32_t* counts = mem.alloc<uint32_t>(n + 1);
    FLUIDSURF_CUDA_CHECK(cudaMemsetAsync(counts + n, 0, sizeof(uint32_t), stream));
    countLeavesKernel<<<blocksFor(n), kThreads, 0, stream>>>(cells, classes, s, counts);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    size_t pairs = 0;
    uint32_t* offsets = scanCounts(counts, n, pairs, mem, stream);
    if (pairs == 0) return out;
    unsigned long long* keys = mem.alloc<unsigned long long>(pairs);
    writeLeavesKernel<<<blocksFor(n), kThreads, 0, stream>>>(cells, classes, s, offsets, keys);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    mem.release(offsets);

    // Sorted unique leaf keys.
    unsigned long long* sorted = mem.alloc<unsigned long long>(pairs);
    runCub(mem, [&](void* scratch, size_t& bytes) {
        return cub::DeviceRadixSort::SortKeys(scratch, bytes, keys, sorted, pairs, 0, 63, stream);
    });
    unsigned long long* leafKeys = keys; // reused
    size_t* unique = mem.alloc<size_t>(1);
    runCub(mem, [&](void* scratch, size_t& bytes) {
        return cub::DeviceSelect::Unique(scratch, bytes, sorted, leafKeys, unique, pairs, stream);
    });
    mem.release(sorted);
    size_t leafCount = 0;
    FLUIDSURF_CUDA_CHECK(
        cudaMemcpyAsync(&leafCount, unique, sizeof(size_t), cudaMemcpyDeviceToHost, stream));
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
    mem.release(unique);

    out.count = leafCount;
    out.masks = mem.alloc<unsigned long long>(8 * leafCount);
    FLUIDSURF_CUDA_CHECK(
        cudaMemsetAsync(out.masks, 0, 8 * leafCount * sizeof(unsigned long long), stream));
    maskKernel<<<blocksFor(n), kThreads, 0, stream>>>(cells, classes, s, leafKeys, leafCount,
                                                      out.masks);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    out.origins = mem.alloc<int32_t>(3 * leafCount);
    originKernel<<<blocksFor(leafCount), kThreads, 0, stream>>>(leafKeys, leafCount, out.origins);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    mem.release(leafKeys);
    return out;
}

} // namespace cuda
} // namespace fluidsurf
