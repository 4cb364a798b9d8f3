// CellIndex.cu - the neighbour structure on the device (thesis §4.2.1-4.2.2): Morton keys of the
// particles' cells, a stable radix sort (CUB), the occupied cells' ranges and a hash table of
// their keys. The arithmetic is the CPU's (neighbors/CellIndex.cc), so keys, order and cells
// are identical.
#include "Stages.cuh"

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_run_length_encode.cuh>
#include <cub/device/device_scan.cuh>

#include <algorithm>
#include <vector>

namespace fluidsurf {
namespace cuda {

namespace {

constexpr int kBoundsBlocks = 512;
constexpr int kThreads = 256;

unsigned blocksFor(size_t n)
{
    return unsigned((n + kThreads - 1) / kThreads);
}

__global__ void boundsKernel(const float3* __restrict__ p, size_t n, float* __restrict__ partial)
{
    __shared__ float s[6][kThreads];
    float lo[3] = {3.4e38f, 3.4e38f, 3.4e38f}, hi[3] = {-3.4e38f, -3.4e38f, -3.4e38f};
    for (size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x; i < n;
         i += size_t(gridDim.x) * blockDim.x) {
        const float3 q = p[i];
        lo[0] = fminf(lo[0], q.x), lo[1] = fminf(lo[1], q.y), lo[2] = fminf(lo[2], q.z);
        hi[0] = fmaxf(hi[0], q.x), hi[1] = fmaxf(hi[1], q.y), hi[2] = fmaxf(hi[2], q.z);
    }
    for (int a = 0; a < 3; ++a)
        s[a][threadIdx.x] = lo[a], s[3 + a][threadIdx.x] = hi[a];
    __syncthreads();
    for (int step = kThreads / 2; step > 0; step /= 2) {
        if (threadIdx.x < step)
            for (int a = 0; a < 3; ++a) {
                s[a][threadIdx.x] = fminf(s[a][threadIdx.x], s[a][threadIdx.x + step]);
                s[3 + a][threadIdx.x] = fmaxf(s[3 + a][threadIdx.x], s[3 + a][threadIdx.x + step]);
            }
        __syncthreads();
    }
    if (threadIdx.x < 6) partial[6 * blockIdx.x + threadIdx.x] = s[threadIdx.x][0];
}

struct Grid
{
    double cellSize, origin[3];
    double maxCell[3]; // dims - 1
};

__global__ void keyKernel(const float3* __restrict__ p, size_t n, Grid g,
                          unsigned long long* __restrict__ keys, uint32_t* __restrict__ index)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const float3 q = p[i];
    const double v[3] = {q.x, q.y, q.z};
    unsigned long long c[3];
    for (int a = 0; a < 3; ++a) {
        const double f = floor((v[a] - g.origin[a]) / g.cellSize);
        c[a] = (unsigned long long)fmin(fmax(f, 0.0), g.maxCell[a]);
    }
    keys[i] = mortonKey(c[0], c[1], c[2]);
    index[i] = uint32_t(i);
}

__global__ void permuteKernel(const uint32_t* __restrict__ order, size_t n,
                              const float3* __restrict__ p, const float* __restrict__ r,
                              float3* __restrict__ sp, float* __restrict__ sr)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const uint32_t src = order[i];
    sp[i] = p[src];
    if (r) sr[i] = r[src];
}

__global__ void cellOfKernel(const uint32_t* __restrict__ starts, size_t cells,
                             uint32_t* __restrict__ cellOf)
{
    const size_t c = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (c >= cells) return;
    for (uint32_t i = starts[c]; i < starts[c + 1]; ++i)
        cellOf[i] = uint32_t(c);
}

__global__ void hashKernel(const unsigned long long* __restrict__ keys, size_t cells,
                           unsigned long long mask, unsigned long long* tableKeys,
                           uint32_t* tableCells)
{
    const size_t c = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (c >= cells) return;
    const unsigned long long key = keys[c];
    for (unsigned long long slot = slotOf(key, mask);; slot = (slot + 1) & mask) {
        const unsigned long long prev = atomicCAS(&tableKeys[slot], kEmptyKey, key);
        if (prev == kEmptyKey) {
            tableCells[slot] = uint32_t(c);
            return;
        }
    }
}

int bitsFor(uint32_t v)
{
    int b = 0;
    while (b < 21 && (1u << b) < v)
        ++b;
    return b;
}

} // namespace

void particleBounds(const float3* positions, size_t n, float lo[3], float hi[3], DeviceMemory& mem,
                    cudaStream_t stream)
{
    const unsigned blocks =
        unsigned(std::max<size_t>(1, std::min<size_t>(kBoundsBlocks, blocksFor(n))));
    float* partial = mem.alloc<float>(6 * blocks);
    boundsKernel<<<blocks, kThreads, 0, stream>>>(positions, n, partial);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    std::vector<float> host(6 * blocks);
    FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(host.data(), partial, host.size() * sizeof(float),
                                         cudaMemcpyDeviceToHost, stream));
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
    mem.release(partial);
    for (int a = 0; a < 3; ++a)
        lo[a] = 3.4e38f, hi[a] = -3.4e38f;
    for (unsigned b = 0; b < blocks; ++b)
        for (int a = 0; a < 3; ++a)
            lo[a] = std::min(lo[a], host[6 * b + a]), hi[a] = std::max(hi[a], host[6 * b + 3 + a]);
}

void sortIntoCells(DeviceCells& cells, const float3* positions, const float* radii, size_t n,
                   DeviceMemory& mem, cudaStream_t stream, StageEvents& events)
{
    cells.count = n;
    Grid g;
    g.cellSize = cells.cellSize;
    for (int a = 0; a < 3; ++a)
        g.origin[a] = cells.origin[a], g.maxCell[a] = double(cells.dims[a] - 1);
    unsigned long long* keys = mem.alloc<unsigned long long>(n);
    uint32_t* index = mem.alloc<uint32_t>(n);
    keyKernel<<<blocksFor(n), kThreads, 0, stream>>>(positions, n, g, keys, index);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());

    // Stable radix sort of (key, input index): within a cell the input order is kept, as the
    // CPU's sort by (key, index) does. Only the bits the grid uses are sorted.
    const int endBit =
        3 * std::max({bitsFor(uint32_t(cells.dims[0])), bitsFor(uint32_t(cells.dims[1])),
                      bitsFor(uint32_t(cells.dims[2])), 1});
    unsigned long long* sortedKeys = mem.alloc<unsigned long long>(n);
    cells.order = mem.alloc<uint32_t>(n);
    runCub(mem, [&](void* scratch, size_t& bytes) {
        return cub::DeviceRadixSort::SortPairs(scratch, bytes, keys, sortedKeys, index, cells.order,
                                               n, 0, endBit, stream);
    });
    mem.release(index);
    cells.positions = mem.alloc<float3>(n);
    cells.radii = radii ? mem.alloc<float>(n) : nullptr;
    permuteKernel<<<blocksFor(n), kThreads, 0, stream>>>(cells.order, n, positions, radii,
                                                         cells.positions, cells.radii);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    events.mark("sort");

    // Occupied cells: run-length encoding of the sorted keys, then offsets.
    unsigned long long* cellKeys = keys; // reused: at most n cells
    uint32_t* counts = mem.alloc<uint32_t>(n + 1);
    size_t* runs = mem.alloc<size_t>(1);
    runCub(mem, [&](void* scratch, size_t& bytes) {
        return cub::DeviceRunLengthEncode::Encode(scratch, bytes, sortedKeys, cellKeys, counts,
                                                  runs, n, stream);
    });
    size_t cellCount = 0;
    FLUIDSURF_CUDA_CHECK(
        cudaMemcpyAsync(&cellCount, runs, sizeof(size_t), cudaMemcpyDeviceToHost, stream));
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
    mem.release(sortedKeys);
    mem.release(runs);
    cells.cellCount = cellCount;
    cells.keys = cellKeys;
    FLUIDSURF_CUDA_CHECK(cudaMemsetAsync(counts + cellCount, 0, sizeof(uint32_t), stream));
    cells.starts = mem.alloc<uint32_t>(cellCount + 1);
    runCub(mem, [&](void* scratch, size_t& bytes) {
        return cub::DeviceScan::ExclusiveSum(scratch, bytes, counts, cells.starts, cellCount + 1,
                                             stream);
    });
    mem.release(counts);
    cells.cellOf = mem.alloc<uint32_t>(n);
    cellOfKernel<<<blocksFor(cellCount), kThreads, 0, stream>>>(cells.starts, cellCount,
                                                                cells.cellOf);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());

    // Hash table: the CPU's size rule (load factor <= 1/2) and slot function.
    size_t size = 16;
    while (size < 2 * cellCount)
        size *= 2;
    cells.tableMask = size - 1;
    cells.tableKeys = mem.alloc<unsigned long long>(size);
    cells.tableCells = mem.alloc<uint32_t>(size);
    FLUIDSURF_CUDA_CHECK(
        cudaMemsetAsync(cells.tableKeys, 0xff, size * sizeof(unsigned long long), stream));
    hashKernel<<<blocksFor(cellCount), kThreads, 0, stream>>>(
        cells.keys, cellCount, cells.tableMask, cells.tableKeys, cells.tableCells);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    events.mark("cells");
}

} // namespace cuda
} // namespace fluidsurf
