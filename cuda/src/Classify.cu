// Classify.cu - neighbour counts, color field and its gradient per particle on the device, one
// thread per particle (the twin of lib/src/classify/Classify.cc).
//
// The classes must be the CPU's exactly, or the band (and so the grid's topology) would differ
// where a particle sits at a threshold. So this file is compiled without FMA contraction and
// repeats the CPU's arithmetic step for step: coordinates relative to the first particle of the
// cell, the same candidate cells (the box of the cell's particles widened by h, in z, y, x
// order), the same kClassLanes float lanes (candidate k adds to lane k % kClassLanes; candidates
// out of reach add exact zeros there) and the same reduction and rule (classify/ClassRule.h).
#include "Stages.cuh"

namespace fluidsurf {
namespace cuda {

namespace {

constexpr int kThreads = 128;

/// Candidate cell box of every occupied cell: the box of its particles widened by h.
__global__ void cellBoxKernel(DeviceCells c, double h, int* __restrict__ boxes)
{
    const size_t cell = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (cell >= c.cellCount) return;
    const uint32_t b = c.starts[cell], e = c.starts[cell + 1];
    const float3 o = c.positions[b];
    double lo[3] = {o.x, o.y, o.z}, hi[3] = {o.x, o.y, o.z};
    for (uint32_t i = b; i < e; ++i) {
        const float3 p = c.positions[i];
        const double v[3] = {p.x, p.y, p.z};
        for (int a = 0; a < 3; ++a)
            lo[a] = fmin(lo[a], v[a]), hi[a] = fmax(hi[a], v[a]);
    }
    for (int a = 0; a < 3; ++a) {
        boxes[6 * cell + a] = int(cellCoord(c, lo[a] - h, a));
        boxes[6 * cell + 3 + a] = int(cellCoord(c, hi[a] + h, a));
    }
}

/// One sum on kClassLanes lanes in registers: the lane a candidate adds to comes round in turn,
/// so the sum is rotated after each candidate instead of indexed (an indexed array would live
/// in local memory).
struct Lanes
{
    static_assert(classify::kClassLanes == 8, "Lanes holds eight");
    float v0 = 0, v1 = 0, v2 = 0, v3 = 0, v4 = 0, v5 = 0, v6 = 0, v7 = 0;
    /// After m candidates with rotate() after each, v0 is lane m % 8; lane l is then:
    __device__ float lane(int l, unsigned m) const
    {
        switch (int((unsigned(l) - m) & 7u)) {
        case 0:
            return v0;
        case 1:
            return v1;
        case 2:
            return v2;
        case 3:
            return v3;
        case 4:
            return v4;
        case 5:
            return v5;
        case 6:
            return v6;
        default:
            return v7;
        }
    }
    __device__ void rotate()
    {
        const float t = v0;
        v0 = v1, v1 = v2, v2 = v3, v3 = v4, v4 = v5, v5 = v6, v6 = v7, v7 = t;
    }
};

__global__ void __launch_bounds__(kThreads)
    classifyKernel(DeviceCells c, ClassifySettings s, const int* __restrict__ boxes,
                   uint8_t* __restrict__ classes)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= c.count) return;
    const uint32_t cell = c.cellOf[i];
    const float3 o = c.positions[c.starts[cell]];
    const float3 p = c.positions[i];
    const float px = float(double(p.x) - double(o.x)), py = float(double(p.y) - double(o.y)),
                pz = float(double(p.z) - double(o.z));
    int c0[3], c1[3];
    for (int a = 0; a < 3; ++a)
        c0[a] = boxes[6 * cell + a], c1[a] = boxes[6 * cell + 3 + a];
    Lanes count, cf, gx, gy, gz;
    unsigned m = 0; // candidates so far
    for (int cz = c0[2]; cz <= c1[2]; ++cz)
        for (int cy = c0[1]; cy <= c1[1]; ++cy)
            for (int cx = c0[0]; cx <= c1[0]; ++cx) {
                const long long at = findCell(c, cx, cy, cz);
                if (at < 0) continue;
                const uint32_t e = c.starts[at + 1];
                for (uint32_t j = c.starts[at]; j < e; ++j, ++m) {
                    const float3 q = c.positions[j];
                    const float dx = float(double(q.x) - double(o.x)) - px;
                    const float dy = float(double(q.y) - double(o.y)) - py;
                    const float dz = float(double(q.z) - double(o.z)) - pz;
                    const float d2 = dx * dx + dy * dy + dz * dz;
                    if (d2 < s.h2) {
                        const float t = s.h2 - d2;
                        float v = s.uniformVolume;
                        if (c.radii) {
                            const double rj = c.radii[j];
                            v = float(8 * rj * rj * rj);
                        }
                        const float vt2 = v * t * t;
                        count.v0 += 1.f;
                        cf.v0 += vt2 * t;
                        gx.v0 += vt2 * dx, gy.v0 += vt2 * dy, gz.v0 += vt2 * dz;
                    }
                    count.rotate(), cf.rotate(), gx.rotate(), gy.rotate(), gz.rotate();
                }
            }
    float lanes[5][classify::kClassLanes];
    for (int l = 0; l < classify::kClassLanes; ++l) {
        lanes[0][l] = count.lane(l, m), lanes[1][l] = cf.lane(l, m);
        lanes[2][l] = gx.lane(l, m), lanes[3][l] = gy.lane(l, m), lanes[4][l] = gz.lane(l, m);
    }
    classes[i] =
        classify::classifyLanes(lanes[0], lanes[1], lanes[2], lanes[3], lanes[4], s.rule).cls;
}

__global__ void countKernel(const uint8_t* __restrict__ classes, size_t n,
                            unsigned long long* counts)
{
    __shared__ unsigned int local[4];
    if (threadIdx.x < 4) local[threadIdx.x] = 0;
    __syncthreads();
    for (size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x; i < n;
         i += size_t(gridDim.x) * blockDim.x)
        atomicAdd(&local[classes[i]], 1u);
    __syncthreads();
    if (threadIdx.x < 4 && local[threadIdx.x])
        atomicAdd(&counts[threadIdx.x], (unsigned long long)local[threadIdx.x]);
}

__global__ void isolatedKernel(DeviceCells c, const uint8_t* __restrict__ classes, bool drop,
                               uint32_t* out, unsigned int* cursor)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= c.count || classes[i] != classify::Isolated) return;
    out[atomicAdd(cursor, 1u)] = c.order[i];
    // Far away: every kernel weight is then exactly zero, like leaving the particle out.
    if (drop) c.positions[i] = make_float3(3e30f, 3e30f, 3e30f);
}

} // namespace

void classifyParticles(const DeviceCells& cells, const ClassifySettings& s, uint8_t* classes,
                       unsigned long long counts[4], DeviceMemory& mem, cudaStream_t stream)
{
    for (int k = 0; k < 4; ++k)
        counts[k] = 0;
    if (cells.count == 0) return;
    int* boxes = mem.alloc<int>(6 * cells.cellCount);
    cellBoxKernel<<<unsigned((cells.cellCount + 255) / 256), 256, 0, stream>>>(
        cells, s.smoothingLength, boxes);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    classifyKernel<<<unsigned((cells.count + kThreads - 1) / kThreads), kThreads, 0, stream>>>(
        cells, s, boxes, classes);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    mem.release(boxes);
    unsigned long long* d = mem.alloc<unsigned long long>(4);
    FLUIDSURF_CUDA_CHECK(cudaMemsetAsync(d, 0, 4 * sizeof(unsigned long long), stream));
    countKernel<<<256, 256, 0, stream>>>(classes, cells.count, d);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    FLUIDSURF_CUDA_CHECK(
        cudaMemcpyAsync(counts, d, 4 * sizeof(unsigned long long), cudaMemcpyDeviceToHost, stream));
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
    mem.release(d);
}

void takeIsolated(DeviceCells& cells, const uint8_t* classes, size_t isolatedCount, bool drop,
                  std::vector<uint32_t>& indices, DeviceMemory& mem, cudaStream_t stream)
{
    indices.assign(isolatedCount, 0);
    if (isolatedCount == 0) return;
    uint32_t* out = mem.alloc<uint32_t>(isolatedCount);
    unsigned int* cursor = mem.alloc<unsigned int>(1);
    FLUIDSURF_CUDA_CHECK(cudaMemsetAsync(cursor, 0, sizeof(unsigned int), stream));
    isolatedKernel<<<unsigned((cells.count + 255) / 256), 256, 0, stream>>>(cells, classes, drop,
                                                                            out, cursor);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(indices.data(), out, isolatedCount * sizeof(uint32_t),
                                         cudaMemcpyDeviceToHost, stream));
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
    mem.release(out);
    mem.release(cursor);
}

} // namespace cuda
} // namespace fluidsurf
