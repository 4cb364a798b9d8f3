// MarchingCubes.cu - marching cubes on the GPU (see facade/MarchingCubes.h): the CPU mesher's
// passes (lib/src/mesh/MarchingCubes.cc), one thread a leaf, each leaf's output at the place the
// prefix sums give it, so the mesh is the CPU's to the bit. Compiled without FMA contraction
// (CMakeLists.txt): the positions and normals round as the CPU's double arithmetic does.
#include "facade/MarchingCubes.h"

#include "DeviceMemory.cuh"
#include "LeafKeys.cuh"
#include "mesh/CellPolygons.h"
#include "mesh/GradientMath.h"

#include <cub/device/device_radix_sort.cuh>
#include <cub/device/device_scan.cuh>

namespace fluidsurf {
namespace cuda {

namespace {

constexpr int kBlock = 128;
constexpr int kKeyBits = 21;

inline unsigned gridFor(size_t n)
{
    return unsigned((n + kBlock - 1) / kBlock);
}

// The words of util/LeafWords.h: bit y * 8 + z of word x.
constexpr uint64_t kZ0 = 0x0101010101010101ULL, kZ7 = kZ0 << 7, kY7 = 0xFFULL << 56;
constexpr uint64_t kYBelow7 = 0x00FFFFFFFFFFFFFFULL;

__device__ inline uint64_t squareAll(uint64_t w)
{
    return w & w >> 1 & w >> 8 & w >> 9;
}
__device__ inline uint64_t squareAny(uint64_t w)
{
    return w | w >> 1 | w >> 8 | w >> 9;
}
__device__ inline uint64_t acrossY(uint64_t w, uint64_t plusY)
{
    return w >> 56 | plusY << 8;
}
__device__ inline uint64_t acrossZ(uint64_t w, uint64_t plusZ)
{
    return (w >> 7 & kZ0) | (plusZ & kZ0) << 1;
}

/// The band on the device: per leaf its 27 neighbours (itself in the middle; -1: none), its 512
/// values (0 where inactive: never read there), its active and inside words.
struct DeviceLeaves
{
    const int* neighbours = nullptr;
    const float* values = nullptr;
    const uint64_t* active = nullptr;
    const uint64_t* in = nullptr;
    const int32_t* origins = nullptr;
};

__device__ inline int neighbourOf(const DeviceLeaves& L, int leaf, int dx, int dy, int dz)
{
    return L.neighbours[size_t(leaf) * 27 + (dx + 1) + 3 * (dy + 1) + 9 * (dz + 1)];
}

/// Value and active state at leaf-local (x, y, z), each coordinate in [-8, 16).
__device__ inline bool readVoxel(const DeviceLeaves& L, int leaf, int x, int y, int z, float& v)
{
    const int n = neighbourOf(L, leaf, x >> 3, y >> 3, z >> 3);
    if (n < 0) return false;
    const int i = (x & 7) << 6 | (y & 7) << 3 | (z & 7);
    v = L.values[size_t(n) * 512 + i];
    return L.active[size_t(n) * 8 + (i >> 6)] >> (i & 63) & 1;
}

/// mesh/Gradient.h's activeGradient at leaf-local l (an active voxel).
__device__ inline void gradientAt(const DeviceLeaves& L, int leaf, const int l[3], double g[3])
{
    float center = 0;
    readVoxel(L, leaf, l[0], l[1], l[2], center);
    for (int a = 0; a < 3; ++a) {
        int lo[3] = {l[0], l[1], l[2]}, hi[3] = {l[0], l[1], l[2]};
        lo[a] -= 1, hi[a] += 1;
        float vlo = 0, vhi = 0;
        const bool onLo = readVoxel(L, leaf, lo[0], lo[1], lo[2], vlo);
        const bool onHi = readVoxel(L, leaf, hi[0], hi[1], hi[2], vhi);
        g[a] = mesh::centralDifference(onLo, vlo, onHi, vhi, center);
    }
}

/// OpenVDB's Mat3 * Vec3 (row-major m): sum in its order.
__device__ inline void multiply(const double* m, const double v[3], double out[3])
{
    for (int i = 0; i < 3; ++i)
        out[i] = v[0] * m[3 * i] + v[1] * m[3 * i + 1] + v[2] * m[3 * i + 2];
}

/// OpenVDB's Vec3d::normalize(): unchanged where the length is within 1e-7 of 0.
__device__ inline void normalize(double v[3])
{
    const double d = sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2]);
    if (!(fabs(d) > 1.0e-7)) return;
    const double s = 1.0 / d;
    v[0] *= s, v[1] *= s, v[2] *= s;
}

/// A leaf's crossing edges (EdgeWords in MarchingCubes.cc).
struct EdgeWords
{
    uint64_t axis[3][8];
    uint32_t before[8];
};

__device__ inline uint32_t edgeVertex(const EdgeWords& e, unsigned i, int axis)
{
    const unsigned w = i >> 6;
    const uint64_t below = (uint64_t(1) << (i & 63)) - 1;
    uint32_t n = e.before[w] + __popcll(e.axis[0][w] & below) + __popcll(e.axis[1][w] & below) +
                 __popcll(e.axis[2][w] & below);
    for (int a = 0; a < axis; ++a)
        n += uint32_t(e.axis[a][w] >> (i & 63) & 1);
    return n;
}

struct Mesh
{
    float3* points = nullptr;
    float3* normals = nullptr; // null: none
    uint32_t* triangles = nullptr;
};

// --- set-up
// ---------------------------------------------------------------------------------------

__global__ void leafKeys(const int32_t* origins, size_t n, int3 keyOrigin, unsigned long long* keys,
                         uint32_t* index)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const uint64_t x = uint64_t((origins[3 * i] >> 3) - keyOrigin.x),
                   y = uint64_t((origins[3 * i + 1] >> 3) - keyOrigin.y),
                   z = uint64_t((origins[3 * i + 2] >> 3) - keyOrigin.z);
    keys[i] = x | y << kKeyBits | z << (2 * kKeyBits);
    index[i] = uint32_t(i);
}

__global__ void findNeighbours(const int32_t* origins, size_t n, int3 keyOrigin,
                               const unsigned long long* sortedKeys, const uint32_t* sortedIndex,
                               int* neighbours)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const int lx = (origins[3 * i] >> 3) - keyOrigin.x,
              ly = (origins[3 * i + 1] >> 3) - keyOrigin.y,
              lz = (origins[3 * i + 2] >> 3) - keyOrigin.z;
    for (int k = 0; k < 27; ++k) {
        const int x = lx + k % 3 - 1, y = ly + k / 3 % 3 - 1, z = lz + k / 9 - 1;
        int found = -1;
        if (x >= 0 && y >= 0 && z >= 0) {
            const unsigned long long key = (unsigned long long)x |
                                           (unsigned long long)y << kKeyBits |
                                           (unsigned long long)z << (2 * kKeyBits);
            const long long at = findLeaf(sortedKeys, n, key);
            if (at >= 0) found = int(sortedIndex[at]);
        }
        neighbours[i * 27 + k] = found;
    }
}

/// One thread a (leaf, word): the word's active values into the leaf's 512, and its inside bits.
__global__ void spreadValues(const uint64_t* active, const uint64_t* valueStart,
                             const float* compact, size_t n, float* values, uint64_t* in)
{
    const size_t t = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (t >= 8 * n) return;
    const size_t leaf = t >> 3;
    const int w = int(t & 7);
    uint64_t first = valueStart[leaf];
    for (int k = 0; k < w; ++k)
        first += __popcll(active[8 * leaf + k]);
    const uint64_t word = active[t];
    uint64_t inside = 0;
    float* out = values + leaf * 512 + 64 * w;
    for (int b = 0; b < 64; ++b) {
        float v = 0;
        if (word >> b & 1) v = compact[first++];
        out[b] = v;
        inside |= uint64_t(mesh::inside(v) && (word >> b & 1)) << b;
    }
    in[t] = inside;
}

// --- pass 1: crossing edges
// -----------------------------------------------------------------------

__global__ void markEdges(DeviceLeaves L, size_t n, EdgeWords* edges, uint64_t* counts)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const int leaf = int(i);
    const int nx = neighbourOf(L, leaf, 1, 0, 0), ny = neighbourOf(L, leaf, 0, 1, 0),
              nz = neighbourOf(L, leaf, 0, 0, 1);
    EdgeWords e;
    uint32_t count = 0;
    for (int x = 0; x < 8; ++x) {
        const uint64_t act = L.active[8 * i + x], in = L.in[8 * i + x];
        const uint64_t nzAct = nz >= 0 ? L.active[8 * size_t(nz) + x] : 0,
                       nzIn = nz >= 0 ? L.in[8 * size_t(nz) + x] : 0;
        const uint64_t nyAct = ny >= 0 ? L.active[8 * size_t(ny) + x] : 0,
                       nyIn = ny >= 0 ? L.in[8 * size_t(ny) + x] : 0;
        const uint64_t ez =
            ((in ^ in >> 1) & act & act >> 1 & ~kZ7) | ((in ^ nzIn << 7) & act & nzAct << 7 & kZ7);
        const uint64_t ey = ((in ^ in >> 8) & act & act >> 8 & kYBelow7) |
                            ((in ^ nyIn << 56) & act & nyAct << 56 & kY7);
        uint64_t ex;
        if (x < 7) {
            ex = (in ^ L.in[8 * i + x + 1]) & act & L.active[8 * i + x + 1];
        } else {
            const uint64_t nxAct = nx >= 0 ? L.active[8 * size_t(nx)] : 0,
                           nxIn = nx >= 0 ? L.in[8 * size_t(nx)] : 0;
            ex = (in ^ nxIn) & act & nxAct;
        }
        e.axis[0][x] = ex, e.axis[1][x] = ey, e.axis[2][x] = ez;
        e.before[x] = count;
        count += __popcll(ex) + __popcll(ey) + __popcll(ez);
    }
    edges[i] = e;
    counts[i] = count;
}

// --- pass 3: the edge vertices
// --------------------------------------------------------------------

__global__ void placeVertices(DeviceLeaves L, size_t n, const EdgeWords* edges,
                              const uint64_t* first, MeshInput in, Mesh mesh)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    const int leaf = int(i);
    const EdgeWords& e = edges[i];
    const int32_t* o = L.origins + 3 * i;
    uint64_t next = first[i];
    for (int x = 0; x < 8; ++x)
        for (uint64_t todo = e.axis[0][x] | e.axis[1][x] | e.axis[2][x]; todo; todo &= todo - 1) {
            const int b = __ffsll(todo) - 1, offset = x << 6 | b;
            const int l[3] = {x, b >> 3, b & 7};
            double ga[3] = {0, 0, 0};
            if (mesh.normals) gradientAt(L, leaf, l, ga);
            const float va = L.values[i * 512 + offset];
            for (int axis = 0; axis < 3; ++axis) {
                if (!(e.axis[axis][x] >> b & 1)) continue;
                int lb[3] = {l[0], l[1], l[2]};
                lb[axis] += 1;
                float vb = 0;
                readVoxel(L, leaf, lb[0], lb[1], lb[2], vb);
                const double t = mesh::crossing(va, vb);
                double p[3] = {double(o[0] + l[0]), double(o[1] + l[1]), double(o[2] + l[2])};
                p[axis] += t;
                double w[3];
                multiply(in.linearT, p, w);
                mesh.points[next] =
                    make_float3(float(w[0] + in.translation[0]), float(w[1] + in.translation[1]),
                                float(w[2] + in.translation[2]));
                if (!mesh.normals) {
                    ++next;
                    continue;
                }
                double gb[3];
                gradientAt(L, leaf, lb, gb);
                double g[3];
                for (int a = 0; a < 3; ++a)
                    g[a] = ga[a] * (1 - t) + gb[a] * t;
                // Where the gradient vanishes: the edge direction, from inside to outside.
                if (!(g[0] * g[0] + g[1] * g[1] + g[2] * g[2] > 0)) g[axis] = va < 0 ? 1.0 : -1.0;
                double m[3];
                multiply(in.jacobianInverseT, g, m);
                normalize(m);
                mesh.normals[next] = make_float3(float(m[0]), float(m[1]), float(m[2]));
                ++next;
            }
        }
}

// --- passes 2 and 4: the cells
// --------------------------------------------------------------------

/// Counts a leaf's triangles and centre vertices (pass 2) or writes them (pass 4).
struct CellSink
{
    bool writes = false;
    uint64_t triangles = 0, centres = 0, cells = 0; // counts; or the next places to write
    Mesh mesh;
    // The vertex star (MarchingCubes.cc's VertexStar): this leaf and those beyond its +x, +y, +z
    // faces, edges and corner, by (x >= 8) | (y >= 8) << 1 | (z >= 8) << 2.
    const EdgeWords* edges[8] = {};
    uint64_t first[8] = {};

    __device__ uint32_t vertex(int x, int y, int z, int axis) const
    {
        const int k = (x >> 3) | (y >> 3) << 1 | (z >> 3) << 2;
        return uint32_t(first[k]) +
               edgeVertex(*edges[k], unsigned((x & 7) << 6 | (y & 7) << 3 | (z & 7)), axis);
    }
    __device__ void triangle(uint32_t a, uint32_t b, uint32_t c)
    {
        if (writes) {
            uint32_t* t = mesh.triangles + 3 * triangles;
            t[0] = a, t[1] = b, t[2] = c;
        }
        ++triangles;
    }
};

/// MarchingCubes.cc's cell(): the polygons of the cell at leaf-local (x, y, z) with corner
/// values c.
__device__ void cell(int x, int y, int z, const float c[8], CellSink& out)
{
    ++out.cells;
    const mesh::CellPolygons polygons(c);
    const int* next = polygons.next;
    const bool ambiguous = polygons.ambiguous;
    uint32_t vertex[12] = {};
    if (out.writes)
        for (int e = 0; e < 12; ++e) {
            if (next[e] < 0) continue;
            const int low = mesh::packed::edgeLowCorner(e);
            vertex[e] = out.vertex(x + (low & 1), y + (low >> 1 & 1), z + (low >> 2 & 1),
                                   mesh::packed::edgeAxis(e));
        }
    polygons.forEach([&](const int* polygon, int n) {
        if (!ambiguous || n == 3) {
            for (int k = 1; k + 1 < n; ++k)
                out.triangle(vertex[polygon[0]], vertex[polygon[k]], vertex[polygon[k + 1]]);
            return;
        }
        const uint32_t centre = uint32_t(out.centres++);
        if (out.writes) {
            double p[3] = {0, 0, 0}, nrm[3] = {0, 0, 0};
            for (int k = 0; k < n; ++k) {
                const float3 q = out.mesh.points[vertex[polygon[k]]];
                p[0] += double(q.x) / n, p[1] += double(q.y) / n, p[2] += double(q.z) / n;
                if (out.mesh.normals) {
                    const float3 m = out.mesh.normals[vertex[polygon[k]]];
                    nrm[0] += double(m.x), nrm[1] += double(m.y), nrm[2] += double(m.z);
                }
            }
            if (nrm[0] * nrm[0] + nrm[1] * nrm[1] + nrm[2] * nrm[2] > 0) normalize(nrm);
            out.mesh.points[centre] = make_float3(float(p[0]), float(p[1]), float(p[2]));
            if (out.mesh.normals)
                out.mesh.normals[centre] = make_float3(float(nrm[0]), float(nrm[1]), float(nrm[2]));
        }
        for (int k = 0; k < n; ++k)
            out.triangle(centre, vertex[polygon[k]], vertex[polygon[(k + 1) % n]]);
    });
}

/// MarchingCubes.cc's cellsOf(): the complete cells with a sign change, in the same order.
__device__ void cellsOf(const DeviceLeaves& L, int leaf, CellSink& out)
{
    const size_t i = size_t(leaf);
    const int nx = neighbourOf(L, leaf, 1, 0, 0), ny = neighbourOf(L, leaf, 0, 1, 0),
              nz = neighbourOf(L, leaf, 0, 0, 1);
    auto act = [&](int n, int x) { return n >= 0 ? L.active[8 * size_t(n) + x] : uint64_t(0); };
    auto ins = [&](int n, int x) { return n >= 0 ? L.in[8 * size_t(n) + x] : uint64_t(0); };
    float c[8];
    auto emit = [&](int x, uint64_t a0, uint64_t a1, uint64_t p0, uint64_t p1, uint64_t valid,
                    int dy, int dz) {
        const uint64_t complete = squareAll(a0) & squareAll(a1) & valid;
        const uint64_t mixed = (squareAny(p0) | squareAny(p1)) & ~(squareAll(p0) & squareAll(p1));
        for (uint64_t todo = complete & mixed; todo; todo &= todo - 1) {
            const int b = __ffsll(todo) - 1, y = (b >> 3) + dy, z = (b & 7) + dz;
            for (int k = 0; k < 8; ++k)
                readVoxel(L, leaf, x + (k & 1), y + (k >> 1 & 1), z + (k >> 2 & 1), c[k]);
            cell(x, y, z, c, out);
        }
    };
    for (int x = 0; x < 7; ++x) {
        const uint64_t a0 = L.active[8 * i + x], a1 = L.active[8 * i + x + 1], p0 = L.in[8 * i + x],
                       p1 = L.in[8 * i + x + 1];
        emit(x, a0, a1, p0, p1, ~kZ7 & kYBelow7, 0, 0);
        emit(x, acrossY(a0, act(ny, x)), acrossY(a1, act(ny, x + 1)), acrossY(p0, ins(ny, x)),
             acrossY(p1, ins(ny, x + 1)), 0x7F, 7, 0);
        emit(x, acrossZ(a0, act(nz, x)), acrossZ(a1, act(nz, x + 1)), acrossZ(p0, ins(nz, x)),
             acrossZ(p1, ins(nz, x + 1)), kZ0 & kYBelow7, 0, 7);
    }
    emit(7, L.active[8 * i + 7], act(nx, 0), L.in[8 * i + 7], ins(nx, 0), ~kZ7 & kYBelow7, 0, 0);
    // Cells with two or three coordinates 7 (22 a leaf).
    for (int k = 0; k < 22; ++k) {
        const int x = k < 8    ? 7
                      : k < 15 ? 7
                               : k - 15,
                  y = k < 8    ? 7
                      : k < 15 ? k - 8
                               : 7,
                  z = k < 8 ? k : 7;
        bool complete = true;
        for (int n = 0; n < 8 && complete; ++n)
            complete = readVoxel(L, leaf, x + (n & 1), y + (n >> 1 & 1), z + (n >> 2 & 1), c[n]);
        if (!complete) continue;
        const int config = mesh::cellSignPattern(c);
        if (config == 0 || config == 255) continue;
        cell(x, y, z, c, out);
    }
}

__global__ void countCells(DeviceLeaves L, size_t n, uint64_t* triangles, uint64_t* centres,
                           uint64_t* cells)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    CellSink out;
    cellsOf(L, int(i), out);
    triangles[i] = out.triangles, centres[i] = out.centres, cells[i] = out.cells;
}

__global__ void writeCells(DeviceLeaves L, size_t n, const EdgeWords* edges, const uint64_t* first,
                           const uint64_t* triangleStart, const uint64_t* centreStart,
                           uint64_t edgeVertices, Mesh mesh)
{
    const size_t i = size_t(blockIdx.x) * blockDim.x + threadIdx.x;
    if (i >= n) return;
    CellSink out;
    out.writes = true;
    out.mesh = mesh;
    out.triangles = triangleStart[i];
    out.centres = edgeVertices + centreStart[i];
    for (int k = 0; k < 8; ++k) {
        const int m = neighbourOf(L, int(i), k & 1, k >> 1 & 1, k >> 2 & 1);
        if (m >= 0) out.edges[k] = edges + m, out.first[k] = first[m];
    }
    cellsOf(L, int(i), out);
}

} // namespace

bool leafKeysFit(const int32_t lo[3], const int32_t hi[3])
{
    for (int a = 0; a < 3; ++a)
        if (!(int64_t(hi[a]) - int64_t(lo[a]) < (int64_t(1) << kKeyBits) - 2)) return false;
    return true;
}

struct MarchingCubesRun::Impl
{
    std::unique_ptr<Stream> ownStream;
    cudaStream_t stream = nullptr;
    std::unique_ptr<DeviceMemory> mem;
    MeshInput input;
    size_t n = 0;
    DeviceLeaves leaves;
    EdgeWords* edges = nullptr;
    uint64_t *first = nullptr, *triangleStart = nullptr, *centreStart = nullptr, *cells = nullptr;
    uint64_t edgeVertices = 0, centres = 0, triangles = 0, cellCount = 0;
};

namespace {

/// Exclusive sums of a (n + 1)-array in place; returns the total (synchronises).
void exclusiveSum(uint64_t* a, size_t n, DeviceMemory& mem, cudaStream_t stream)
{
    uint64_t* out = mem.alloc<uint64_t>(n + 1);
    runCub(mem, [&](void* scratch, size_t& bytes) {
        return cub::DeviceScan::ExclusiveSum(scratch, bytes, a, out, n + 1, stream);
    });
    FLUIDSURF_CUDA_CHECK(
        cudaMemcpyAsync(a, out, (n + 1) * sizeof(uint64_t), cudaMemcpyDeviceToDevice, stream));
    mem.release(out);
}

uint64_t lastOf(const uint64_t* a, size_t n, cudaStream_t stream)
{
    uint64_t v = 0;
    FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(&v, a + n, sizeof v, cudaMemcpyDeviceToHost, stream));
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(stream));
    return v;
}

} // namespace

MarchingCubesRun::MarchingCubesRun(const MeshInput& input, void* stream) : mImpl(new Impl)
{
    Impl& m = *mImpl;
    m.ownStream.reset(new Stream(stream));
    m.stream = m.ownStream->get();
    m.mem.reset(new DeviceMemory(m.stream));
    m.input = input;
    m.n = input.leafCount;
    const size_t n = m.n;
    DeviceMemory& mem = *m.mem;
    cudaStream_t s = m.stream;
    if (n == 0) return;
    if (n >= (size_t(1) << 31)) throw Error("GPU marching cubes: more than 2^31 leaves");

    const int32_t* origins = mem.upload(input.leafOrigins, 3 * n);
    const uint64_t* active = mem.upload(input.leafActive, 8 * n);
    const uint64_t* valueStart = mem.upload(input.valueStart, n + 1);
    const float* compact = mem.upload(input.values, size_t(input.valueStart[n]));
    // the caller may free its arrays once this returns (the synchronisations below wait for the
    // copies): keep no pointer to them
    m.input.leafOrigins = nullptr, m.input.leafActive = nullptr;
    m.input.valueStart = nullptr, m.input.values = nullptr;
    const int3 keyOrigin = make_int3(input.keyOrigin[0], input.keyOrigin[1], input.keyOrigin[2]);

    // Each leaf's neighbours: keys sorted, then 27 binary searches a leaf.
    unsigned long long* keys = mem.alloc<unsigned long long>(n);
    unsigned long long* sortedKeys = mem.alloc<unsigned long long>(n);
    uint32_t* index = mem.alloc<uint32_t>(n);
    uint32_t* sortedIndex = mem.alloc<uint32_t>(n);
    leafKeys<<<gridFor(n), kBlock, 0, s>>>(origins, n, keyOrigin, keys, index);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    runCub(mem, [&](void* scratch, size_t& bytes) {
        return cub::DeviceRadixSort::SortPairs(scratch, bytes, keys, sortedKeys, index, sortedIndex,
                                               int(n), 0, 3 * kKeyBits, s);
    });
    int* neighbours = mem.alloc<int>(27 * n);
    findNeighbours<<<gridFor(n), kBlock, 0, s>>>(origins, n, keyOrigin, sortedKeys, sortedIndex,
                                                 neighbours);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    mem.release(keys), mem.release(sortedKeys), mem.release(index), mem.release(sortedIndex);

    float* values = mem.alloc<float>(512 * n);
    uint64_t* in = mem.alloc<uint64_t>(8 * n);
    spreadValues<<<gridFor(8 * n), kBlock, 0, s>>>(active, valueStart, compact, n, values, in);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    mem.release(compact), mem.release(valueStart);
    m.leaves = DeviceLeaves{neighbours, values, active, in, origins};

    m.edges = mem.alloc<EdgeWords>(n);
    m.first = mem.alloc<uint64_t>(n + 1);
    FLUIDSURF_CUDA_CHECK(cudaMemsetAsync(m.first + n, 0, sizeof(uint64_t), s));
    markEdges<<<gridFor(n), kBlock, 0, s>>>(m.leaves, n, m.edges, m.first);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    exclusiveSum(m.first, n, mem, s);

    m.triangleStart = mem.alloc<uint64_t>(n + 1);
    m.centreStart = mem.alloc<uint64_t>(n + 1);
    m.cells = mem.alloc<uint64_t>(n + 1);
    FLUIDSURF_CUDA_CHECK(cudaMemsetAsync(m.triangleStart + n, 0, sizeof(uint64_t), s));
    FLUIDSURF_CUDA_CHECK(cudaMemsetAsync(m.centreStart + n, 0, sizeof(uint64_t), s));
    FLUIDSURF_CUDA_CHECK(cudaMemsetAsync(m.cells + n, 0, sizeof(uint64_t), s));
    countCells<<<gridFor(n), kBlock, 0, s>>>(m.leaves, n, m.triangleStart, m.centreStart, m.cells);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    exclusiveSum(m.triangleStart, n, mem, s);
    exclusiveSum(m.centreStart, n, mem, s);
    exclusiveSum(m.cells, n, mem, s);
    m.edgeVertices = lastOf(m.first, n, s);
    m.triangles = lastOf(m.triangleStart, n, s);
    m.centres = lastOf(m.centreStart, n, s);
    m.cellCount = lastOf(m.cells, n, s);
}

MarchingCubesRun::~MarchingCubesRun()
{
    mImpl->mem.reset(); // frees on the stream and waits
    mImpl->ownStream.reset();
}

uint64_t MarchingCubesRun::vertexCount() const
{
    return mImpl->edgeVertices + mImpl->centres;
}
uint64_t MarchingCubesRun::triangleCount() const
{
    return mImpl->triangles;
}
uint64_t MarchingCubesRun::cellCount() const
{
    return mImpl->cellCount;
}
size_t MarchingCubesRun::deviceBytes() const
{
    return mImpl->mem->peakBytes();
}

void MarchingCubesRun::finish(Vec3f* points, Vec3f* normals, uint32_t* triangles)
{
    Impl& m = *mImpl;
    if (m.n == 0) return;
    DeviceMemory& mem = *m.mem;
    cudaStream_t s = m.stream;
    const uint64_t vertices = vertexCount();
    Mesh mesh;
    mesh.points = mem.alloc<float3>(vertices);
    if (normals) mesh.normals = mem.alloc<float3>(vertices);
    mesh.triangles = mem.alloc<uint32_t>(3 * m.triangles);
    placeVertices<<<gridFor(m.n), kBlock, 0, s>>>(m.leaves, m.n, m.edges, m.first, m.input, mesh);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    writeCells<<<gridFor(m.n), kBlock, 0, s>>>(m.leaves, m.n, m.edges, m.first, m.triangleStart,
                                               m.centreStart, m.edgeVertices, mesh);
    FLUIDSURF_CUDA_CHECK(cudaGetLastError());
    static_assert(sizeof(Vec3f) == sizeof(float3), "Vec3f is three floats");
    FLUIDSURF_CUDA_CHECK(
        cudaMemcpyAsync(points, mesh.points, vertices * sizeof(float3), cudaMemcpyDeviceToHost, s));
    if (normals)
        FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(normals, mesh.normals, vertices * sizeof(float3),
                                             cudaMemcpyDeviceToHost, s));
    FLUIDSURF_CUDA_CHECK(cudaMemcpyAsync(
        triangles, mesh.triangles, 3 * m.triangles * sizeof(uint32_t), cudaMemcpyDeviceToHost, s));
    FLUIDSURF_CUDA_CHECK(cudaStreamSynchronize(s));
}

} // namespace cuda
} // namespace fluidsurf
