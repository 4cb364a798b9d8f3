// GatherField.cu - the SSP07 / ZB05 gather on the GPU, one block per VDB leaf (see
// facade/FieldGather.h). The finish from sums to phi is lib/src/field/FieldMath.h, the same code
// the CPU runs. Deterministic: every run sums each voxel's particles in the same order.
#include "facade/FieldGather.h"

#include "Stages.cuh"

namespace fluidsurf {
namespace cuda {

namespace {

constexpr int kThreads = 256; // 2 voxels of the 8^3 leaf per thread
constexpr int kVoxelsPerThread = 512 / kThreads;
constexpr int kTile = 256;      // particles staged in shared memory at a time
constexpr int kCellChunk = 512; // occupied-cell lookups per pass
static_assert(kCellChunk % kThreads == 0 && kThreads % 32 == 0, "whole warps, whole rounds");

struct Params
{
    DeviceCells cells;
    const int32_t* leafOrigins;
    const unsigned long long* leafActive;
    double dx, R;
    field::FieldConstants constants;
    float* out;
    const uint32_t* compactOffsets; // non-null: out holds only the active voxels (see Stages.cuh)
};

struct Sums
{
    float w = 0, d0 = 0, d1 = 0, d2 = 0, r = 0, g0 = 0, g1 = 0, g2 = 0, m0 = 0, m1 = 0, m2 = 0,
          m3 = 0, m4 = 0, m5 = 0;
};

__global__ void __launch_bounds__(kThreads) gatherKernel(Params p)
{
    __shared__ uint32_t cellBegin[kCellChunk], cellPrefix[kCellChunk + 1];
    __shared__ float4 tile[kTile];
    __shared__ int cellsInChunk;
    __shared__ int warpFound[kThreads / 32];

    const int leaf = blockIdx.x;
    const int3 origin = make_int3(p.leafOrigins[3 * leaf], p.leafOrigins[3 * leaf + 1],
                                  p.leafOrigins[3 * leaf + 2]);
    const double o[3] = {origin.x * p.dx, origin.y * p.dx, origin.z * p.dx};
    const float invR2 = float(1 / (p.R * p.R));

    int voxel[kVoxelsPerThread];
    bool active[kVoxelsPerThread];
    float vx[kVoxelsPerThread], vy[kVoxelsPerThread], vz[kVoxelsPerThread];
    Sums acc[kVoxelsPerThread];
    for (int k = 0; k < kVoxelsPerThread; ++k) {
        const int v = threadIdx.x + k * kThreads; // OpenVDB order: x * 64 + y * 8 + z
        voxel[k] = v;
        active[k] = (p.leafActive[8 * leaf + (v >> 6)] >> (v & 63)) & 1ull;
        vx[k] = float((v >> 6) * p.dx), vy[k] = float(((v >> 3) & 7) * p.dx),
        vz[k] = float((v & 7) * p.dx);
    }

    // The occupied cells overlapping the leaf's voxel box widened by R.
    long long c0[3], c1[3];
    for (int a = 0; a < 3; ++a) {
        c0[a] = cellCoord(p.cells, o[a] - p.R, a);
        c1[a] = cellCoord(p.cells, o[a] + 7 * p.dx + p.R, a);
    }
    const long long nx = c1[0] - c0[0] + 1, ny = c1[1] - c0[1] + 1, nz = c1[2] - c0[2] + 1;
    const long long boxCells = nx * ny * nz;
    for (long long chunk = 0; chunk < boxCells; chunk += kCellChunk) {
        if (threadIdx.x == 0) cellsInChunk = 0;
        __syncthreads();
        // The occupied cells of the chunk, compacted in candidate order (warp ballots and the
        // warps' counts): the particles are summed in the same order on every run, so the
        // values, and the files written from them, are reproducible bit for bit.
        for (int round = 0; round < kCellChunk / kThreads; ++round) {
            const long long c = chunk + round * kThreads + threadIdx.x;
            long long at = -1;
            if (c < boxCells) {
                const long long cx = c0[0] + c % nx, cy = c0[1] + (c / nx) % ny,
                                cz = c0[2] + c / (nx * ny);
                at = findCell(p.cells, cx, cy, cz);
            }
            const unsigned found = __ballot_sync(0xffffffffu, at >= 0);
            const int lane = threadIdx.x & 31, warp = threadIdx.x >> 5;
            if (lane == 0) warpFound[warp] = __popc(found);
            __syncthreads();
            int slot = cellsInChunk + __popc(found & ((1u << lane) - 1u));
            for (int w = 0; w < warp; ++w)
                slot += warpFound[w];
            if (at >= 0) {
                cellBegin[slot] = p.cells.starts[at];
                cellPrefix[slot + 1] = p.cells.starts[at + 1] - p.cells.starts[at];
            }
            __syncthreads();
            if (threadIdx.x == 0)
                for (int w = 0; w < kThreads / 32; ++w)
                    cellsInChunk += warpFound[w];
            __syncthreads();
        }
        const int cells = cellsInChunk;
        if (threadIdx.x == 0) {
            cellPrefix[0] = 0;
            for (int i = 0; i < cells; ++i)
                cellPrefix[i + 1] += cellPrefix[i];
        }
        __syncthreads();
        const uint32_t total = cellPrefix[cells];
        for (uint32_t base = 0; base < total; base += kTile) {
            const uint32_t flat = base + threadIdx.x;
            if (threadIdx.x < kTile) {
                float4 q = make_float4(3e30f, 3e30f, 3e30f, 0.f); // past the end: adds nothing
                if (flat < total) {
                    int lo = 0, hi = cells - 1; // last cell whose prefix <= flat
                    while (lo < hi) {
                        const int mid = (lo + hi + 1) / 2;
                        if (cellPrefix[mid] <= flat)
                            lo = mid;
                        else
                            hi = mid - 1;
                    }
                    const uint32_t i = cellBegin[lo] + (flat - cellPrefix[lo]);
                    const float3 x = p.cells.positions[i];
                    // Leaf-local coordinates, computed like the CPU (difference in double).
                    q = make_float4(float(double(x.x) - o[0]), float(double(x.y) - o[1]),
                                    float(double(x.z) - o[2]),
                                    p.cells.radii ? p.cells.radii[i] : 0.f);
                }
                tile[threadIdx.x] = q;
            }
            __syncthreads();
            const int n = min(kTile, int(total - base));
            for (int k = 0; k < kVoxelsPerThread; ++k) {
                if (!active[k]) continue;
                Sums& a = acc[k];
                for (int j = 0; j < n; ++j) {
                    const float4 q = tile[j];
                    const float ex = q.x - vx[k], ey = q.y - vy[k], ez = q.z - vz[k];
                    const float s2 = (ex * ex + ey * ey + ez * ez) * invR2;
                    float t = 1.f - s2;
                    if (!(t > 1e-6f)) continue; // the CPU's cut-off (FieldValue.h)
                    const float t2 = t * t, wt = t2 * t;
                    a.w += wt;
                    a.d0 += wt * ex, a.d1 += wt * ey, a.d2 += wt * ez;
                    a.r += wt * q.w;
                    const float gx = t2 * ex, gy = t2 * ey, gz = t2 * ez;
                    a.g0 += gx, a.g1 += gy, a.g2 += gz;
                    a.m0 += gx * ex, a.m1 += gx * ey, a.m2 += gx * ez;
                    a.m3 += gy * ey, a.m4 += gy * ez, a.m5 += gz * ez;
                }
            }
            __syncthreads();
        }
    }
    for (int k = 0; k < kVoxelsPerThread; ++k) {
        float value = p.constants.background;
        if (active[k]) {
            const Sums& a = acc[k];
            field::FieldSums s;
            s.w = a.w, s.r = a.r;
            s.d[0] = a.d0, s.d[1] = a.d1, s.d[2] = a.d2;
            s.g[0] = a.g0, s.g[1] = a.g1, s.g[2] = a.g2;
            s.m[0] = a.m0, s.m[1] = a.m1, s.m[2] = a.m2, s.m[3] = a.m3, s.m[4] = a.m4,
            s.m[5] = a.m5;
            value = field::fieldValue(s, p.constants);
        }
        if (!p.compactOffsets) {
            p.out[size_t(leaf) * 512 + voxel[k]] = value;
        } else if (active[k]) {
            // Rank of the voxel among the leaf's active voxels: the bits below it.
            const int v = voxel[k], word = v >> 6;
            uint32_t rank = __popcll(p.leafActive[8 * leaf + word] & ((1ull << (v & 63)) - 1));
            for (int w = 0; w < word; ++w)
                rank += __popcll(p.leafActive[8 * leaf + w]);
            p.out[p.compactOffsets[leaf] + rank] = value;
        }
    }
}

} // namespace

field::FieldConstants fieldConstants(const FieldSettings& s, bool perParticleRadii)
{
    field::FieldConstants c;
    c.influenceRadius = s.influenceRadius;
    c.radius = s.radius;
    c.perParticleRadii = perParticleRadii;
    c.ssp07 = s.ssp07;
    c.tLow = s.tLow, c.tHigh = s.tHigh;
    c.background = s.background;
    return c;
}

void gatherLeaves(const DeviceCells& cells, const int32_t* origins, const unsigned long long* masks,
                  size_t leafCount, double voxelSize, const field::FieldConstants& constants,
                  float* out, cudaStream_t stream, const uint32_t* compactOffsets)
{
    if (leafCount == 0) return;
    Params p{};
    p.cells = cells;
    p.leafOrigins = origins;
    p.leafActive = masks;
    p.dx = voxelSize, p.R = constants.influenceRadius;
    p.constants = constants;
    p.out = out;
    p.compactOffsets = compactOffsets;
    gatherKernel<<<unsigned(leafCount), kThreads, 0, stream>>>(p);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
}

std::vector<float> gatherField(const GatherInput& in, GatherTimes* times, void* streamPtr)
{
    std::vector<float> out(in.leafCount * 512, in.field.background);
    if (in.leafCount == 0) return out;
    if (!(in.cellSize > 0 && in.field.voxelSize > 0 && in.field.influenceRadius > 0))
        throw Error("gatherField: invalid sizes");
    if (in.tableSize == 0 || (in.tableSize & (in.tableSize - 1)))
        throw Error("gatherField: the cell hash table size must be a power of two");
    const Stream ownStream(streamPtr);
    const cudaStream_t stream = ownStream.get();
    DeviceMemory mem(stream);
    StageEvents events(stream);
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
    const int32_t* origins = mem.upload(in.leafOrigins, 3 * in.leafCount);
    const unsigned long long* masks =
        mem.upload(reinterpret_cast<const unsigned long long*>(in.leafActive), 8 * in.leafCount);
    const field::FieldConstants constants = fieldConstants(in.field, in.radii != nullptr);
    float* values = mem.alloc<float>(out.size());
    events.mark("upload");
    gatherLeaves(cells, origins, masks, in.leafCount, in.field.voxelSize, constants, values,
                 stream);
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
