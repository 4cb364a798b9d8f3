// LeafCells.cuh - a block's walk over the occupied cells of a leaf's box, in the CPU's order (z,
// then y, then x: neighbors::CellIndex::forEachCellInBox), and the compaction that keeps what the
// block's threads find in that order. Shared by the leaf gathers (GatherField.cu,
// AnisotropicGather.cu), whose sums depend on that order.
#pragma once

#include "Check.cuh"
#include "DeviceCells.cuh"

#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace cuda {

constexpr int kLeafThreads = 256; // a block a leaf
constexpr int kCellChunk = 512;   // occupied-cell lookups per pass
static_assert(kCellChunk % kLeafThreads == 0 && kLeafThreads % 32 == 0,
              "whole warps, whole rounds");

/// The box of a leaf's active voxels, leaf-local voxel indices [first, last] from its 8 mask
/// words (word x, bit y 8 + z); false when none is active.
__device__ inline bool activeVoxelBounds(const unsigned long long* words, int first[3], int last[3])
{
    for (int a = 0; a < 3; ++a)
        first[a] = 8, last[a] = -1;
    unsigned long long yz = 0;
    for (int x = 0; x < 8; ++x)
        if (words[x]) {
            first[0] = min(first[0], x), last[0] = x;
            yz |= words[x];
        }
    if (last[0] < 0) return false;
    unsigned z = 0;
    for (int y = 0; y < 8; ++y)
        if (const unsigned row = unsigned(yz >> (8 * y)) & 0xffu) {
            first[1] = min(first[1], y), last[1] = y;
            z |= row;
        }
    first[2] = __ffs(z) - 1, last[2] = 31 - __clz(z);
    return true;
}

/// The block's threads with `keep`, numbered in thread order from `kept` (shared), which then
/// counts them too: where each writes, in order. All threads call it (it synchronises).
__device__ inline uint32_t keptSlot(bool keep, int* warpFound, uint32_t& kept)
{
    const unsigned found = __ballot_sync(0xffffffffu, keep);
    const int lane = threadIdx.x & 31, warp = threadIdx.x >> 5;
    if (lane == 0) warpFound[warp] = __popc(found);
    __syncthreads();
    uint32_t at = kept + __popc(found & ((1u << lane) - 1u));
    for (int w = 0; w < warp; ++w)
        at += warpFound[w];
    __syncthreads(); // (every thread has read `kept`)
    if (threadIdx.x == 0)
        for (int w = 0; w < kLeafThreads / 32; ++w)
            kept += warpFound[w];
    __syncthreads();
    return at;
}

/// Walks the occupied cells of the leaf's box in the CPU's order (z, then y, then x), a chunk of
/// cells at a time, and calls visit(cellBegin, cellPrefix, cells) with the chunk's occupied cells
/// compacted in that order (all threads, block-uniform).
template <typename Visit>
__device__ inline void forEachCellChunk(const DeviceCells& cellIndex, const double o[3],
                                        const double lo[3], const double hi[3], uint32_t* cellBegin,
                                        uint32_t* cellPrefix, int* warpFound,
                                        uint32_t& cellsInChunk, Visit&& visit)
{
    long long c0[3], c1[3];
    for (int a = 0; a < 3; ++a) {
        c0[a] = cellCoord(cellIndex, o[a] + lo[a], a);
        c1[a] = cellCoord(cellIndex, o[a] + hi[a], a);
    }
    const long long nx = c1[0] - c0[0] + 1, ny = c1[1] - c0[1] + 1, nz = c1[2] - c0[2] + 1;
    const long long boxCells = nx * ny * nz;
    for (long long chunk = 0; chunk < boxCells; chunk += kCellChunk) {
        if (threadIdx.x == 0) cellsInChunk = 0;
        __syncthreads();
        for (int round = 0; round < kCellChunk / kLeafThreads; ++round) {
            const long long c = chunk + round * kLeafThreads + threadIdx.x;
            long long at = -1;
            if (c < boxCells)
                at = findCell(cellIndex, c0[0] + c % nx, c0[1] + (c / nx) % ny,
                              c0[2] + c / (nx * ny));
            const uint32_t slot = keptSlot(at >= 0, warpFound, cellsInChunk);
            if (at >= 0) {
                cellBegin[slot] = cellIndex.starts[at];
                cellPrefix[slot + 1] = cellIndex.starts[at + 1] - cellIndex.starts[at];
            }
        }
        __syncthreads();
        const int cells = int(cellsInChunk);
        if (threadIdx.x == 0) {
            cellPrefix[0] = 0;
            for (int i = 0; i < cells; ++i)
                cellPrefix[i + 1] += cellPrefix[i];
        }
        __syncthreads();
        visit(cellBegin, cellPrefix, cells);
        __syncthreads();
    }
}

/// Particle flat of a chunk's cells (flat < cellPrefix[cells]).
__device__ inline uint32_t particleAt(const uint32_t* cellBegin, const uint32_t* cellPrefix,
                                      int cells, uint32_t flat)
{
    int lo = 0, hi = cells - 1; // the last cell whose prefix <= flat
    while (lo < hi) {
        const int mid = (lo + hi + 1) / 2;
        if (cellPrefix[mid] <= flat)
            lo = mid;
        else
            hi = mid - 1;
    }
    return cellBegin[lo] + (flat - cellPrefix[lo]);
}

/// How many items (particles, kernels) each of leafCount leaves gathers: countKernel's output,
/// brought to the host (synchronises). Then the leaves in batches whose scratch holds at most
/// `limit` items (a leaf with more runs alone): run(begin, end, offsets, total), offsets[i] where
/// leaf begin + i's items start.
template <typename Run>
void forEachLeafBatch(const uint32_t* deviceCounts, size_t leafCount, unsigned long long limit,
                      cudaStream_t stream, Run&& run)
{
    std::vector<uint32_t> counts(leafCount);
    FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(counts.data(), deviceCounts, leafCount * sizeof(uint32_t),
                                         cudaMemcpyDeviceToHost, stream));
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
    std::vector<unsigned long long> offsets;
    for (size_t begin = 0, end = 0; begin < leafCount; begin = end) {
        offsets.clear();
        unsigned long long total = 0;
        for (end = begin; end < leafCount && (end == begin || total + counts[end] <= limit); ++end)
            offsets.push_back(total), total += counts[end];
        run(begin, end, offsets, total);
    }
}

} // namespace cuda
} // namespace fluidsurf
