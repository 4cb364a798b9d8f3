// Smooth.cu - post-processing's smoothing on the GPU (see facade/Smooth.h): lib/src/post/
// Smooth.cc's steps kernel by kernel. Compiled without FMA contraction, every operation written
// in the order OpenVDB's Vec3d gives the CPU (componentwise sums and products, dot products
// x + y + z from the left, lengths as the root of that), so the points come out bit for bit.
// Where the CPU walks only some points (the flat steps' active list), a kernel walks all of them
// and leaves the others as the CPU leaves them; the thin test's answer is whether any point
// qualifies, which does not depend on the order the cells are walked in.
#include "Check.cuh"
#include "DeviceCells.cuh"
#include "DeviceMemory.cuh"
#include "Stages.cuh"
#include "facade/Smooth.h"
#include "post/SmoothSteps.h"

#include <fluidsurf/Error.h>

#include <cuda_runtime.h>
#include <math_constants.h>

#include <cmath>
#include <vector>

namespace fluidsurf {
namespace cuda {

namespace {

using namespace post::steps;

constexpr unsigned kThreads = 256;

unsigned blocksOf(size_t n)
{
    return unsigned((n + kThreads - 1) / kThreads);
}

/// OpenVDB's Vec3d arithmetic, operation for operation.
struct D3
{
    double x, y, z;
};
__device__ __forceinline__ D3 add(D3 a, D3 b)
{
    return {a.x + b.x, a.y + b.y, a.z + b.z};
}
__device__ __forceinline__ D3 sub(D3 a, D3 b)
{
    return {a.x - b.x, a.y - b.y, a.z - b.z};
}
__device__ __forceinline__ D3 scale(D3 a, double s)
{
    return {a.x * s, a.y * s, a.z * s};
}
__device__ __forceinline__ D3 divide(D3 a, double s)
{
    return {a.x / s, a.y / s, a.z / s};
}
__device__ __forceinline__ double dot(D3 a, D3 b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}
__device__ __forceinline__ double lengthSqr(D3 a)
{
    return a.x * a.x + a.y * a.y + a.z * a.z;
}
__device__ __forceinline__ double length(D3 a)
{
    return sqrt(a.x * a.x + a.y * a.y + a.z * a.z);
}
__device__ __forceinline__ D3 cross(D3 a, D3 b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}
__device__ __forceinline__ bool same(D3 a, D3 b)
{
    return a.x == b.x && a.y == b.y && a.z == b.z;
}

/// The mesh and its tables on the device.
struct Mesh
{
    const uint3* tris;
    const uint32_t *cornerStart, *cornerTris, *ringStart, *ring;
    const uint8_t* fixed;
    size_t points, triangles;
    __device__ uint32_t count(size_t v) const { return ringStart[v + 1] - ringStart[v]; }
    __device__ bool moves(size_t v) const { return !fixed[v] && count(v) > 0; }
    /// the mean of v's neighbours' values (Rings::mean)
    __device__ D3 mean(const D3* value, size_t v) const
    {
        D3 sum{0.0, 0.0, 0.0};
        for (uint32_t i = ringStart[v]; i < ringStart[v + 1]; ++i)
            sum = add(sum, value[ring[i]]);
        return divide(sum, double(count(v)));
    }
    /// triangle t's side cross product at points p (post::sideCross)
    __device__ D3 sideCross(const D3* p, uint32_t t) const
    {
        const uint3 c = tris[t];
        const D3 a = p[c.x];
        return cross(sub(p[c.y], a), sub(p[c.z], a));
    }
    /// v's area-weighted normal, not normalised (post::areaNormal, AreaNormals)
    __device__ D3 areaNormal(const D3* p, size_t v) const
    {
        D3 n{0.0, 0.0, 0.0};
        for (uint32_t i = cornerStart[v]; i < cornerStart[v + 1]; ++i)
            n = add(n, sideCross(p, cornerTris[i]));
        return n;
    }
};

/// n made unit length; false where it has none (Smooth.cc's unitNormal)
__device__ __forceinline__ bool unit(D3& n)
{
    const double len = length(n);
    if (!(len > 0)) return false;
    n = divide(n, len);
    return true;
}

/// to + (at - to) shortened to at most bound (Smooth.cc's within)
__device__ __forceinline__ D3 within(D3 at, D3 to, double bound)
{
    const D3 offset = sub(at, to);
    const double dist = length(offset);
    return dist > bound ? add(to, scale(offset, bound / dist)) : at;
}

__global__ void toDoubleKernel(const float3* in, size_t n, D3* p, D3* from)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= n) return;
    const float3 q = in[v];
    p[v] = from[v] = D3{double(q.x), double(q.y), double(q.z)};
}

__global__ void toFloatKernel(const D3* p, size_t n, float3* out)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= n) return;
    out[v] = make_float3(float(p[v].x), float(p[v].y), float(p[v].z));
}

/// Every point's area normal, as AreaNormals::compute sums it (each triangle's cross product,
/// then each point's in its corners' order).
__global__ void crossKernel(Mesh m, const D3* p, D3* crossOf)
{
    const size_t t = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (t < m.triangles) crossOf[t] = m.sideCross(p, uint32_t(t));
}

__global__ void sumKernel(Mesh m, const D3* crossOf, D3* normals)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= m.points) return;
    D3 n{0.0, 0.0, 0.0};
    for (uint32_t i = m.cornerStart[v]; i < m.cornerStart[v + 1]; ++i)
        n = add(n, crossOf[m.cornerTris[i]]);
    normals[v] = n;
}

/// One Taubin step (stepAlongNormals).
__global__ void taubinKernel(Mesh m, const D3* normals, const D3* from, const D3* p, D3* next,
                             double factor, double bound)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= m.points) return;
    next[v] = p[v];
    D3 n = normals[v];
    if (!m.moves(v) || !unit(n)) return;
    const D3 moved = add(p[v], scale(n, factor * dot(n, sub(m.mean(p, v), p[v]))));
    next[v] = within(moved, from[v], bound);
}

/// One plain Laplacian step of the curvature's copy (flatWeights).
__global__ void shapeKernel(Mesh m, const D3* shape, D3* next)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= m.points) return;
    next[v] = m.moves(v) ? scale(add(shape[v], m.mean(shape, v)), 0.5) : shape[v];
}

/// Each point's curvature on the copy, infinity where it counts as curved (flatWeights).
__global__ void kappaKernel(Mesh m, const D3* shape, const D3* normals, double curved,
                            double* kappa)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= m.points) return;
    kappa[v] = CUDART_INF;
    D3 n = normals[v];
    if (!m.moves(v) || !unit(n)) return;
    double edges = 0;
    for (uint32_t i = m.ringStart[v]; i < m.ringStart[v + 1]; ++i)
        edges += lengthSqr(sub(shape[m.ring[i]], shape[v]));
    edges /= double(m.count(v));
    if (!(edges > 0)) return;
    const double k = 2 * fabs(dot(n, sub(m.mean(shape, v), shape[v]))) / edges;
    if (k < curved) kappa[v] = k;
}

/// markThin's unit normals (zero where none) and float positions.
__global__ void unitKernel(size_t n, const D3* p, const D3* normals, D3* unitOf, float3* at)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= n) return;
    at[v] = make_float3(float(p[v].x), float(p[v].y), float(p[v].z));
    D3 u = normals[v];
    unitOf[v] = unit(u) ? u : D3{0.0, 0.0, 0.0};
}

/// markThin: kappa infinity where another part of the surface faces the point within reach.
__global__ void thinKernel(DeviceCells cells, const D3* p, const D3* unitOf, double reach,
                           double* kappa)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= cells.count) return;
    const D3 n = unitOf[v];
    if (!isfinite(kappa[v]) || lengthSqr(n) == 0) return;
    const D3 x = p[v];
    const double lo[3] = {x.x - reach, x.y - reach, x.z - reach};
    const double hi[3] = {x.x + reach, x.y + reach, x.z + reach};
    long long c0[3], c1[3];
    for (int a = 0; a < 3; ++a)
        c0[a] = cellCoord(cells, lo[a], a), c1[a] = cellCoord(cells, hi[a], a);
    for (long long cz = c0[2]; cz <= c1[2]; ++cz)
        for (long long cy = c0[1]; cy <= c1[1]; ++cy)
            for (long long cx = c0[0]; cx <= c1[0]; ++cx) {
                const long long c = findCell(cells, cx, cy, cz);
                if (c < 0) continue;
                for (uint32_t i = cells.starts[c]; i < cells.starts[c + 1]; ++i) {
                    const uint32_t u = cells.order[i];
                    if (dot(unitOf[u], n) < kFacing && lengthSqr(sub(p[u], x)) < reach * reach) {
                        kappa[v] = CUDART_INF;
                        return;
                    }
                }
            }
}

/// The largest kappa over the point and its ring (flatWeights' feature rings).
__global__ void spreadKernel(Mesh m, const double* kappa, double* spread)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= m.points) return;
    double k = kappa[v];
    for (uint32_t i = m.ringStart[v]; i < m.ringStart[v + 1]; ++i) {
        const double o = kappa[m.ring[i]];
        k = k < o ? o : k; // (std::max)
    }
    spread[v] = k;
}

__global__ void weightKernel(size_t n, const double* kappa, double flat, double curved,
                             double* weight)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= n) return;
    const double k = kappa[v];
    weight[v] = k <= flat ? 1 : k >= curved ? 0 : (curved - k) / (curved - flat);
}

struct Bounds
{
    double maxMove, flatMove;
    /// a point's bound for its weight (flatten's bound)
    __device__ double of(double w) const { return maxMove + (flatMove - maxMove) * w * w; }
};

/// One flat step (flatten): the points of weight > 0 only; the others stay as they are in both
/// buffers.
__global__ void flatKernel(Mesh m, const double* weight, const D3* from, const D3* p, D3* next,
                           D3* normalOf, bool fresh, Bounds b)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= m.points || !(weight[v] > 0)) return;
    if (fresh) normalOf[v] = m.areaNormal(p, v);
    next[v] = p[v];
    const D3 normal = normalOf[v];
    const double len = length(normal);
    if (!(len > 0)) return;
    const D3 n = divide(normal, len);
    D3 sum{0.0, 0.0, 0.0}; // the mean of the flat neighbours (flatMean)
    uint32_t count = 0;
    for (uint32_t i = m.ringStart[v]; i < m.ringStart[v + 1]; ++i) {
        const uint32_t u = m.ring[i];
        if (weight[u] > 0) sum = add(sum, p[u]), ++count;
    }
    const D3 mean = count ? divide(sum, double(count)) : p[v];
    const D3 moved = add(p[v], scale(n, kFlatLambda * weight[v] * dot(n, sub(mean, p[v]))));
    next[v] = within(moved, from[v], b.of(weight[v]));
}

__global__ void movedKernel(size_t n, const D3* p, const D3* start, D3* moved)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v < n) moved[v] = sub(p[v], start[v]);
}

/// One step of the slow part's low pass.
__global__ void slowKernel(Mesh m, const D3* moved, D3* next)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= m.points) return;
    next[v] = m.count(v) ? scale(add(moved[v], m.mean(moved, v)), 0.5) : moved[v];
}

/// The slow part given back in the share the point moved.
__global__ void giveBackKernel(Mesh m, const D3* moved, const double* weight, const D3* from, D3* p,
                               Bounds b)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= m.points || !m.moves(v)) return;
    p[v] = within(sub(p[v], scale(moved[v], weight[v])), from[v], b.of(weight[v]));
}

/// unfold: the points of triangles turned by more than 60 degrees since start.
__global__ void turnedKernel(Mesh m, const D3* start, const D3* p, uint8_t* back, int* any)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v >= m.points) return;
    back[v] = 0;
    if (same(p[v], start[v])) return;
    for (uint32_t i = m.cornerStart[v]; i < m.cornerStart[v + 1]; ++i) {
        const uint3 t = m.tris[m.cornerTris[i]];
        const D3 before = cross(sub(start[t.y], start[t.x]), sub(start[t.z], start[t.x]));
        const D3 after = cross(sub(p[t.y], p[t.x]), sub(p[t.z], p[t.x]));
        if (dot(after, before) < kTurned * length(after) * length(before)) {
            back[v] = 1;
            *any = 1;
            return;
        }
    }
}

__global__ void backKernel(size_t n, const uint8_t* back, const D3* start, D3* p)
{
    const size_t v = blockIdx.x * size_t(blockDim.x) + threadIdx.x;
    if (v < n && back[v]) p[v] = start[v];
}

} // namespace

void smoothPoints(const SmoothInput& in, Vec3f* out, void* streamArg)
{
    const size_t nv = in.pointCount, nt = in.triangleCount;
    if (nv == 0) return;
    Stream owned(streamArg);
    const cudaStream_t stream = owned.get();
    DeviceMemory mem(stream);
    Mesh m;
    m.points = nv, m.triangles = nt;
    m.tris = reinterpret_cast<const uint3*>(mem.upload(in.triangles, 3 * nt));
    m.cornerStart = mem.upload(in.cornerStart, nv + 1);
    m.cornerTris = mem.upload(in.cornerTris, 3 * nt);
    m.ringStart = mem.upload(in.ringStart, nv + 1);
    m.ring = mem.upload(in.ring, in.ringStart[nv]);
    m.fixed = mem.upload(in.fixed, nv);
    const float3* points = mem.upload(reinterpret_cast<const float3*>(in.points), nv);
    D3* p = mem.alloc<D3>(nv);
    D3* next = mem.alloc<D3>(nv);
    D3* from = mem.alloc<D3>(nv);
    D3* normals = mem.alloc<D3>(nv);
    D3* crossOf = mem.alloc<D3>(std::max<size_t>(nt, 1));
    const unsigned pb = blocksOf(nv), tb = blocksOf(std::max<size_t>(nt, 1));
    auto check = [] { FLUIDSURF_CUDA_CHECK(cudaGetLastError()); };
    auto computeNormals = [&](const D3* at) {
        crossKernel<<<tb, kThreads, 0, stream>>>(m, at, crossOf);
        sumKernel<<<pb, kThreads, 0, stream>>>(m, crossOf, normals);
        check();
    };
    toDoubleKernel<<<pb, kThreads, 0, stream>>>(points, nv, p, from);
    check();
    for (int step = 0; step < 2 * in.rounds; ++step) {
        computeNormals(p);
        taubinKernel<<<pb, kThreads, 0, stream>>>(m, normals, from, p, next,
                                                  step % 2 ? kMu : kLambda, in.maxMove);
        check();
        std::swap(p, next);
    }
    if (in.flatten && in.flatMove > 0 && in.voxel > 0) {
        // the weights (flatWeights): the curvature on a copy smoothed by plain steps
        D3* shape = mem.alloc<D3>(nv);
        FLUIDSURF_CUDA_CHECK(
            cudaMemcpyAsync(shape, p, nv * sizeof(D3), cudaMemcpyDeviceToDevice, stream));
        for (int step = 0; step < kShapeSteps; ++step) {
            shapeKernel<<<pb, kThreads, 0, stream>>>(m, shape, next);
            check();
            std::swap(shape, next);
        }
        computeNormals(shape);
        const double flat = kFlatCurvature / in.voxel, curved = kCurvedCurvature / in.voxel;
        double* kappa = mem.alloc<double>(nv);
        double* spread = mem.alloc<double>(nv);
        kappaKernel<<<pb, kThreads, 0, stream>>>(m, shape, normals, curved, kappa);
        check();
        // markThin: a cell index of the points (as floats) with cells of the reach
        computeNormals(p);
        D3* unitOf = shape; // (the copy is not read again)
        float3* at = mem.alloc<float3>(nv);
        unitKernel<<<pb, kThreads, 0, stream>>>(nv, p, normals, unitOf, at);
        check();
        const double reach = kThinReach * in.voxel;
        DeviceCells cells;
        float lo[3], hi[3];
        particleBounds(at, nv, lo, hi, mem, stream);
        uint32_t dims[3];
        in.cellGrid(lo, hi, reach, cells.origin, dims);
        cells.cellSize = reach;
        for (int a = 0; a < 3; ++a) {
            if (dims[a] >= (1u << 21)) // (the device's cell keys: 21 bits an axis)
                throw Error("the mesh spans more cells than the GPU's cell keys hold");
            cells.dims[a] = int(dims[a]);
        }
        StageEvents events(stream);
        sortIntoCells(cells, at, nullptr, nv, mem, stream, events);
        thinKernel<<<pb, kThreads, 0, stream>>>(cells, p, unitOf, reach, kappa);
        check();
        for (int ring = 0; ring < kFeatureRings; ++ring) {
            spreadKernel<<<pb, kThreads, 0, stream>>>(m, kappa, spread);
            check();
            std::swap(kappa, spread);
        }
        double* weight = spread;
        weightKernel<<<pb, kThreads, 0, stream>>>(nv, kappa, flat, curved, weight);
        check();
        // the flat steps (flatten), from start
        const Bounds bounds{in.maxMove, in.flatMove};
        D3* start = mem.alloc<D3>(nv);
        for (D3* to : {start, next})
            FLUIDSURF_CUDA_CHECK(
                cudaMemcpyAsync(to, p, nv * sizeof(D3), cudaMemcpyDeviceToDevice, stream));
        D3* normalOf = normals;
        for (int step = 0; step < kFlatSteps; ++step) {
            flatKernel<<<pb, kThreads, 0, stream>>>(m, weight, from, p, next, normalOf,
                                                    step % kNormalSteps == 0, bounds);
            check();
            std::swap(p, next);
        }
        // the slow part of the moves, given back
        D3* moved = nt >= nv ? crossOf : mem.alloc<D3>(nv); // (no more normals)
        movedKernel<<<pb, kThreads, 0, stream>>>(nv, p, start, moved);
        check();
        for (int step = 0; step < kSlowSteps; ++step) {
            slowKernel<<<pb, kThreads, 0, stream>>>(m, moved, next);
            check();
            std::swap(moved, next);
        }
        giveBackKernel<<<pb, kThreads, 0, stream>>>(m, moved, weight, from, p, bounds);
        check();
        // unfold: turned triangles' points back to start, until none is left
        uint8_t* back = mem.alloc<uint8_t>(nv);
        int* any = mem.alloc<int>(1);
        for (;;) {
            int found = 0;
            FLUIDSURF_CUDA_CHECK(cudaMemsetAsync(any, 0, sizeof(int), stream));
            turnedKernel<<<pb, kThreads, 0, stream>>>(m, start, p, back, any);
            check();
            FLUIDSURF_CUDA_CHECK(
                cudaMemcpyAsync(&found, any, sizeof(int), cudaMemcpyDeviceToHost, stream));
            FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
            if (!found) break;
            backKernel<<<pb, kThreads, 0, stream>>>(nv, back, start, p);
            check();
        }
    }
    float3* result = mem.alloc<float3>(nv);
    toFloatKernel<<<pb, kThreads, 0, stream>>>(p, nv, result);
    check();
    FLUIDSURF_CUDA_CHECK(
        cudaMemcpyAsync(out, result, nv * sizeof(float3), cudaMemcpyDeviceToHost, stream));
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
}

} // namespace cuda
} // namespace fluidsurf
