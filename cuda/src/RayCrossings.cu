// RayCrossings.cu - post::componentsOfParticles' ray test on the GPU (see facade/
// RayCrossings.h): one thread a column sets up its triangles' planes (post/RayPlanes.h), one
// thread a particle walks its column's planes in their order, as the CPU's lanes do.
#include "Check.cuh"
#include "DeviceMemory.cuh"
#include "facade/RayCrossings.h"
#include "post/RayPlanes.h"

#include <cuda_runtime.h>
#include <math_constants.h>

namespace fluidsurf {
namespace cuda {

namespace {

constexpr unsigned kThreads = 256;
constexpr uint32_t kNone = 0xffffffffu;
/// Components one ray's crossings are gathered into (a ray through more is left to the CPU).
constexpr int kKept = 48;

unsigned blocksOf(size_t n)
{
    return unsigned((n + kThreads - 1) / kThreads);
}

struct Rays
{
    int axis, u, v;
    double u0, v0, cell, nudgeU, nudgeV;
    long long nu;
    size_t columns;
    const uint32_t *start, *tris, *first, *sorted;
    __device__ double cornerU(size_t c) const { return u0 + double((long long)c % nu) * cell; }
    __device__ double cornerV(size_t c) const { return v0 + double((long long)c / nu) * cell; }
};

/// Each column's planes, in its triangles' order; comp kNone for a triangle of no component
/// or edge-on to the rays. The column of each of its particles' slots too.
__global__ void planesKernel(Rays r, const float3* points, const uint3* triangles,
                             const uint32_t* ofPoint, post::RayPlane* planes, uint32_t* comp,
                             int8_t* sign, uint32_t* columnOfSlot)
{
    const size_t c = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (c >= r.columns || r.first[c] == r.first[c + 1]) return;
    for (uint32_t s = r.first[c]; s < r.first[c + 1]; ++s)
        columnOfSlot[s] = uint32_t(c);
    const double cu0 = r.cornerU(c), cv0 = r.cornerV(c);
    for (uint32_t k = r.start[c]; k < r.start[c + 1]; ++k) {
        const uint3 t = triangles[r.tris[k]];
        comp[k] = kNone;
        const uint32_t owner = ofPoint[t.x];
        if (owner == kNone) continue;
        const float3 pa = points[t.x], pb = points[t.y], pe = points[t.z];
        const double a[3] = {pa.x, pa.y, pa.z}, b[3] = {pb.x, pb.y, pb.z},
                     e[3] = {pe.x, pe.y, pe.z};
        int s;
        if (!post::rayPlane(a, b, e, cu0, cv0, r.axis, r.u, r.v, planes[k], s)) continue;
        comp[k] = owner, sign[k] = int8_t(s);
    }
}

__device__ __forceinline__ double along(const float3& q, int axis)
{
    return axis == 0 ? double(q.x) : axis == 1 ? double(q.y) : double(q.z);
}

__global__ void particlesKernel(Rays r, size_t slots, const uint32_t* columnOfSlot,
                                const float3* particles, const post::RayPlane* planes,
                                const uint32_t* comp, const int8_t* sign, const uint8_t* outward,
                                uint32_t* out, int* overflow)
{
    const size_t at = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (at >= slots) return;
    const size_t c = columnOfSlot[at];
    const uint32_t i = r.sorted[at];
    const float3 q = particles[i];
    const double u = along(q, r.u) + r.nudgeU - r.cornerU(c),
                 v = along(q, r.v) + r.nudgeV - r.cornerV(c), x0 = along(q, r.axis);
    uint32_t keptComp[kKept];
    int keptCount[kKept];
    double keptNearest[kKept];
    int kept = 0, winding = 0;
    for (uint32_t k = r.start[c]; k < r.start[c + 1]; ++k) {
        if (comp[k] == kNone) continue;
        double x;
        if (!post::crossesAhead(planes[k], u, v, x0, x)) continue;
        winding += sign[k];
        int j = 0;
        while (j < kept && keptComp[j] != comp[k])
            ++j;
        if (j == kept) {
            if (kept == kKept) {
                *overflow = 1;
                return;
            }
            keptComp[j] = comp[k], keptCount[j] = 1, keptNearest[j] = x, ++kept;
        } else {
            ++keptCount[j];
            keptNearest[j] = x < keptNearest[j] ? x : keptNearest[j]; // (std::min)
        }
    }
    uint32_t holder = kNone;
    if (winding > 0) {
        double nearest = CUDART_INF;
        for (int j = 0; j < kept; ++j)
            if ((keptCount[j] & 1) && outward[keptComp[j]] && keptNearest[j] < nearest)
                nearest = keptNearest[j], holder = keptComp[j];
    }
    out[i] = holder;
}

} // namespace

bool componentsOnDevice(const RayInput& in, uint32_t* out, void* streamArg)
{
    const size_t slots = in.columnCount ? in.first[in.columnCount] : 0;
    Stream owned(streamArg);
    const cudaStream_t stream = owned.get();
    DeviceMemory mem(stream);
    uint32_t* result = mem.alloc<uint32_t>(in.particleCount);
    FLUIDSURF_CUDA_CHECK(
        cudaMemsetAsync(result, 0xff, in.particleCount * sizeof(uint32_t), stream));
    int* overflow = mem.alloc<int>(1);
    FLUIDSURF_CUDA_CHECK(cudaMemsetAsync(overflow, 0, sizeof(int), stream));
    if (slots > 0) {
        const size_t entries = in.start[in.columnCount];
        Rays r;
        r.axis = in.axis, r.u = in.u, r.v = in.v;
        r.u0 = in.u0, r.v0 = in.v0, r.cell = in.cell, r.nudgeU = in.nudgeU, r.nudgeV = in.nudgeV;
        r.nu = in.nu, r.columns = in.columnCount;
        r.start = mem.upload(in.start, in.columnCount + 1);
        r.tris = mem.upload(in.tris, entries);
        r.first = mem.upload(in.first, in.columnCount + 1);
        r.sorted = mem.upload(in.sorted, slots);
        const float3* points =
            mem.upload(reinterpret_cast<const float3*>(in.points), in.pointCount);
        const uint3* triangles =
            reinterpret_cast<const uint3*>(mem.upload(in.triangles, 3 * in.triangleCount));
        const uint32_t* ofPoint = mem.upload(in.ofPoint, in.pointCount);
        const uint8_t* outward = mem.upload(in.outward, in.componentCount);
        const float3* particles =
            mem.upload(reinterpret_cast<const float3*>(in.particles), in.particleCount);
        post::RayPlane* planes = mem.alloc<post::RayPlane>(entries);
        uint32_t* comp = mem.alloc<uint32_t>(entries);
        int8_t* sign = mem.alloc<int8_t>(entries);
        uint32_t* columnOfSlot = mem.alloc<uint32_t>(slots);
        planesKernel<<<blocksOf(in.columnCount), kThreads, 0, stream>>>(
            r, points, triangles, ofPoint, planes, comp, sign, columnOfSlot);
        FLUIDSURF_CUDA_CHECK(cudaGetLastError());
        particlesKernel<<<blocksOf(slots), kThreads, 0, stream>>>(
            r, slots, columnOfSlot, particles, planes, comp, sign, outward, result, overflow);
        FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    }
    int overflowed = 0;
    FLUIDSURF_CUDA_CHECK(
        cudaMemcpyAsync(&overflowed, overflow, sizeof(int), cudaMemcpyDeviceToHost, stream));
    FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(out, result, in.particleCount * sizeof(uint32_t),
                                         cudaMemcpyDeviceToHost, stream));
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
    return !overflowed;
}

} // namespace cuda
} // namespace fluidsurf
