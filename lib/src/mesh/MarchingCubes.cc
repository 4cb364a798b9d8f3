// MarchingCubes.cc - marching cubes over the active band (see MarchingCubes.h for the passes).
#include "mesh/MarchingCubes.h"

#include "mesh/Gradient.h"

#include <fluidsurf/Error.h>

#include <openvdb/tree/LeafManager.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <bitset>
#include <chrono>
#include <numeric>

namespace fluidsurf {
namespace mesh {

namespace {

using openvdb::Coord;
using FloatTree = openvdb::FloatTree;
using FloatLeaf = FloatTree::LeafNodeType;
/// Per active voxel: (number of the first vertex on its +x/+y/+z edges) << 3 | crossing-axis bits.
using IndexTree = openvdb::Int64Tree;
using IndexLeaf = IndexTree::LeafNodeType;

// Corner n of a cell is at offset (n & 1, n >> 1 & 1, n >> 2 & 1).
constexpr int kCorner[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0}, {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
// Faces, corners counter-clockwise seen from outside the cell: -x, +x, -y, +y, -z, +z.
constexpr int kFace[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4}, {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

// The 12 cell edges: edge (a, b) of adjacent corners has index edgeIndex[a][b]; its lower
// corner and axis locate the grid edge (and so the vertex) it shares with other cells.
struct EdgeTable
{
    int index[8][8];
    int lowCorner[12], axis[12];
    EdgeTable()
    {
        int n = 0;
        for (int a = 0; a < 8; ++a)
            for (int b = 0; b < 8; ++b) index[a][b] = -1;
        for (int a = 0; a < 8; ++a)
            for (int bit = 0; bit < 3; ++bit) {
                if (a >> bit & 1) continue;
                const int b = a | 1 << bit;
                index[a][b] = index[b][a] = n;
                lowCorner[n] = a, axis[n] = bit;
                ++n;
            }
    }
};
const EdgeTable kEdges;

// Crossing points are kept off the corners: a corner value of exactly 0 would otherwise put
// several vertices on one point and leave zero-area triangles.
constexpr double kEdgeMargin = 1e-3;

inline bool inside(float v) { return v < 0; }

inline double crossing(float a, float b)
{
    return std::clamp(double(a) / (double(a) - double(b)), kEdgeMargin, 1 - kEdgeMargin);
}

/// Value and active state of the voxel at local offset (x, y, z) + d of leaf, through the leaf
/// when it is inside and through the accessor otherwise.
inline bool probe(const FloatLeaf& leaf, FloatAccessor& acc, int x, int y, int z, int dx, int dy, int dz, float& v)
{
    x += dx, y += dy, z += dz;
    if ((unsigned(x) | unsigned(y) | unsigned(z)) < FloatLeaf::DIM) {
        const openvdb::Index i = FloatLeaf::coordToOffset(Coord(x, y, z));
        v = leaf.getValue(i);
        return leaf.isValueOn(i);
    }
    return acc.probeValue(leaf.origin() + Coord(x, y, z), v);
}

/// One leaf's triangles, and the centre vertices it added (numbered kLocalVertex | i until the
/// leaves are joined).
constexpr uint32_t kLocalVertex = 0x80000000u;
struct LeafMesh
{
    std::vector<std::array<uint32_t, 3>> triangles;
    std::vector<Vec3f> points, normals;
};

struct Passes
{
    const FloatTree& tree;
    const openvdb::math::Transform& xform;
    IndexTree& index;
    openvdb::tree::LeafManager<IndexTree>& leaves;
    std::vector<uint64_t> first;  // per leaf: number of its first vertex (after pass 1)

    const FloatLeaf& valueLeaf(const IndexLeaf& leaf) const { return *tree.probeConstLeaf(leaf.origin()); }

    // Pass 1: crossing bits per active voxel, count per leaf.
    void markEdges()
    {
        std::vector<uint64_t> counts(leaves.leafCount(), 0);
        tbb::parallel_for(leaves.leafRange(), [&](const openvdb::tree::LeafManager<IndexTree>::LeafRange& range) {
            FloatAccessor acc(tree);
            for (auto leaf = range.begin(); leaf; ++leaf) {
                const FloatLeaf& values = valueLeaf(*leaf);
                uint64_t n = 0;
                for (auto v = values.cbeginValueOn(); v; ++v) {
                    const Coord l = FloatLeaf::offsetToLocalCoord(v.pos());
                    const bool in = inside(*v);
                    int64_t bits = 0;
                    for (int a = 0; a < 3; ++a) {
                        float w;
                        if (probe(values, acc, l.x(), l.y(), l.z(), a == 0, a == 1, a == 2, w) && inside(w) != in)
                            bits |= int64_t(1) << a;
                    }
                    leaf->setValueOnly(v.pos(), bits);
                    n += std::bitset<3>(uint64_t(bits)).count();
                }
                counts[leaf.pos()] = n;
            }
        });
        first.assign(counts.size() + 1, 0);
        std::partial_sum(counts.begin(), counts.end(), first.begin() + 1);
    }

    // Pass 2: vertex numbers into the index tree, positions and normals into the mesh.
    void placeVertices(TriangleMesh& mesh)
    {
        mesh.points.resize(first.back());
        mesh.normals.resize(first.back());
        tbb::parallel_for(leaves.leafRange(), [&](const openvdb::tree::LeafManager<IndexTree>::LeafRange& range) {
            FloatAccessor acc(tree);
            for (auto leaf = range.begin(); leaf; ++leaf) {
                const FloatLeaf& values = valueLeaf(*leaf);
                uint64_t next = first[leaf.pos()];
                for (auto v = values.cbeginValueOn(); v; ++v) {
                    const int64_t bits = leaf->getValue(v.pos());
                    leaf->setValueOnly(v.pos(), int64_t(next) << 3 | bits);
                    const Coord a = v.getCoord();
                    for (int axis = 0; axis < 3; ++axis) {
                        if (!(bits >> axis & 1)) continue;
                        Coord b = a;
                        b[axis] += 1;
                        const float va = *v, vb = acc.getValue(b);
                        const double t = crossing(va, vb);
                        openvdb::Vec3d p = a.asVec3d();
                        p[axis] += t;
                        const openvdb::Vec3d w = xform.indexToWorld(p);
                        const openvdb::Vec3f nrm = edgeNormal(acc, xform, a, b, t, va);
                        mesh.points[next] = Vec3f(float(w.x()), float(w.y()), float(w.z()));
                        mesh.normals[next] = Vec3f(nrm.x(), nrm.y(), nrm.z());
                        ++next;
                    }
                }
            }
        });
    }

    // Pass 3: triangles of every complete cell with a sign change, per leaf.
    size_t triangulate(std::vector<LeafMesh>& perLeaf, const TriangleMesh& mesh)
    {
        perLeaf.assign(leaves.leafCount(), {});
        std::atomic<size_t> surfaceCells{0};
        tbb::parallel_for(leaves.leafRange(), [&](const openvdb::tree::LeafManager<IndexTree>::LeafRange& range) {
            FloatAccessor acc(tree);
            openvdb::tree::ValueAccessor<const IndexTree> idx(index);
            size_t cells = 0;
            for (auto leaf = range.begin(); leaf; ++leaf) {
                const FloatLeaf& values = valueLeaf(*leaf);
                auto& out = perLeaf[leaf.pos()];
                for (auto v = values.cbeginValueOn(); v; ++v) {
                    const Coord l = FloatLeaf::offsetToLocalCoord(v.pos());
                    float c[8];
                    c[0] = *v;
                    bool complete = true;
                    for (int n = 1; n < 8 && complete; ++n)
                        complete = probe(values, acc, l.x(), l.y(), l.z(), kCorner[n][0], kCorner[n][1], kCorner[n][2], c[n]);
                    if (!complete) continue;
                    int config = 0;
                    for (int n = 0; n < 8; ++n) config |= int(inside(c[n])) << n;
                    if (config == 0 || config == 255) continue;
                    ++cells;
                    cell(v.getCoord(), c, idx, mesh, out);
                }
            }
            surfaceCells += cells;
        });
        return surfaceCells;
    }

    // The polygons of one cell. On each face, a segment runs from the edge where the walk
    // (counter-clockwise seen from outside the cell) enters the inside to the edge where it
    // leaves; such segments chain into closed polygons, oriented counter-clockwise seen from
    // outside the fluid. A face with four crossings pairs them by the sign of the bilinear
    // saddle value, the same in both cells of the face.
    // A polygon is fanned from its first vertex, except in a cell with such an ambiguous face:
    // there two polygon vertices on that face may be joined by a fan diagonal in both cells,
    // which would give that edge four triangles. Those polygons get a centre vertex instead.
    template <typename IndexAccessor>
    void cell(const Coord& origin, const float c[8], IndexAccessor& idx, const TriangleMesh& mesh, LeafMesh& out) const
    {
        int next[12];
        std::fill(next, next + 12, -1);
        bool ambiguous = false;
        for (const auto& face : kFace) {
            int enter[2], leave[2], ne = 0, nl = 0;
            for (int k = 0; k < 4; ++k) {
                const int a = face[k], b = face[(k + 1) & 3];
                if (inside(c[a]) == inside(c[b])) continue;
                if (inside(c[b])) enter[ne++] = k;
                else leave[nl++] = k;
            }
            if (ne == 0) continue;
            auto edge = [&](int k) { return kEdges.index[face[k]][face[(k + 1) & 3]]; };
            if (ne == 1) {
                next[edge(enter[0])] = edge(leave[0]);
                continue;
            }
            ambiguous = true;
            const double v0 = c[face[0]], v1 = c[face[1]], v2 = c[face[2]], v3 = c[face[3]];
            const double saddle = (v0 * v2 - v1 * v3) / (v0 + v2 - v1 - v3);
            const int step = inside(float(saddle)) ? 3 : 1;  // inside joined: previous edge; else next
            for (int e = 0; e < 2; ++e) next[edge(enter[e])] = edge((enter[e] + step) & 3);
        }
        uint32_t vertex[12];
        for (int e = 0; e < 12; ++e) {
            if (next[e] < 0) continue;
            Coord g = origin;
            for (int a = 0; a < 3; ++a) g[a] += kCorner[kEdges.lowCorner[e]][a];
            const int64_t packed = idx.getValue(g);
            const int axis = kEdges.axis[e];
            vertex[e] = uint32_t((packed >> 3) + std::bitset<3>(uint64_t(packed & ((1 << axis) - 1))).count());
        }
        bool done[12] = {};
        for (int start = 0; start < 12; ++start) {
            if (next[start] < 0 || done[start]) continue;
            int polygon[12], n = 0;
            for (int e = start; !done[e]; e = next[e]) done[e] = true, polygon[n++] = e;
            if (!ambiguous || n == 3) {
                for (int k = 1; k + 1 < n; ++k)
                    out.triangles.push_back({vertex[polygon[0]], vertex[polygon[k]], vertex[polygon[k + 1]]});
                continue;
            }
            openvdb::Vec3d p(0.0), nrm(0.0);
            for (int k = 0; k < n; ++k) {
                const Vec3f &q = mesh.points[vertex[polygon[k]]], &m = mesh.normals[vertex[polygon[k]]];
                p += openvdb::Vec3d(q.x, q.y, q.z) / n, nrm += openvdb::Vec3d(m.x, m.y, m.z);
            }
            if (nrm.lengthSqr() > 0) nrm.normalize();
            const uint32_t centre = kLocalVertex | uint32_t(out.points.size());
            out.points.push_back(Vec3f(float(p.x()), float(p.y()), float(p.z())));
            out.normals.push_back(Vec3f(float(nrm.x()), float(nrm.y()), float(nrm.z())));
            for (int k = 0; k < n; ++k)
                out.triangles.push_back({centre, vertex[polygon[k]], vertex[polygon[(k + 1) % n]]});
        }
    }
};

/// Drop vertices no triangle uses and renumber (order kept).
void dropUnusedVertices(TriangleMesh& mesh)
{
    std::vector<uint32_t> map(mesh.points.size(), 0);
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t) map[v] = 1;
    uint32_t n = 0;
    for (size_t i = 0; i < map.size(); ++i) {
        if (!map[i]) continue;
        mesh.points[n] = mesh.points[i], mesh.normals[n] = mesh.normals[i];
        map[i] = n++;
    }
    mesh.points.resize(n), mesh.normals.resize(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.triangles.size(), 4096), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i)
            for (uint32_t& v : mesh.triangles[i]) v = map[v];
    });
}

} // namespace

TriangleMesh marchingCubes(const openvdb::FloatGrid& grid, MeshStats* stats)
{
    const auto start = std::chrono::steady_clock::now();
    // Active tiles (rare in level sets) become voxels so that every active value is a leaf voxel.
    openvdb::FloatTree::Ptr voxelized;
    const FloatTree* tree = &grid.tree();
    if (tree->hasActiveTiles()) {
        voxelized = std::make_shared<FloatTree>(*tree);
        voxelized->voxelizeActiveTiles();
        tree = voxelized.get();
    }
    IndexTree index(*tree, int64_t(0), openvdb::TopologyCopy());
    openvdb::tree::LeafManager<IndexTree> leaves(index);
    Passes passes{*tree, grid.transform(), index, leaves, {}};
    TriangleMesh mesh;
    passes.markEdges();
    if (passes.first.back() >= kLocalVertex)
        throw ValueError("the level set has more than 2^31 surface vertices; mesh it in parts");
    passes.placeVertices(mesh);
    std::vector<LeafMesh> perLeaf;
    const size_t cells = passes.triangulate(perLeaf, mesh);
    // Join the leaves in order: centre vertices after the edge vertices.
    size_t triangles = 0, vertices = mesh.points.size();
    for (const LeafMesh& l : perLeaf) triangles += l.triangles.size(), vertices += l.points.size();
    if (vertices >= kLocalVertex) throw ValueError("the level set has more than 2^31 surface vertices; mesh it in parts");
    mesh.triangles.reserve(triangles);
    for (const LeafMesh& l : perLeaf) {
        const uint32_t base = uint32_t(mesh.points.size());
        for (auto t : l.triangles) {
            for (uint32_t& v : t)
                if (v & kLocalVertex) v = base + (v & ~kLocalVertex);
            mesh.triangles.push_back(t);
        }
        mesh.points.insert(mesh.points.end(), l.points.begin(), l.points.end());
        mesh.normals.insert(mesh.normals.end(), l.normals.begin(), l.normals.end());
    }
    dropUnusedVertices(mesh);
    if (stats) {
        stats->surfaceCells = cells;
        stats->vertices = mesh.points.size();
        stats->triangles = mesh.triangles.size();
        stats->seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return mesh;
}

} // namespace mesh
} // namespace fluidsurf
