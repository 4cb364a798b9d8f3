// MarchingCubes.cc - marching cubes over the active band (see MarchingCubes.h for the passes).
#include "mesh/MarchingCubes.h"

#include "mesh/CellPolygons.h"
#include "mesh/Gradient.h"
#include "mesh/LeafBits.h"

#include <fluidsurf/Error.h>

#include <openvdb/tree/LeafManager.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <numeric>
#include <unordered_map>

namespace fluidsurf {
namespace mesh {

namespace {

using openvdb::Coord;
using FloatTree = openvdb::FloatTree;
using FloatLeaf = FloatTree::LeafNodeType;
/// Per active voxel: (number of the first vertex on its +x/+y/+z edges) << 3 | crossing-axis bits.
using IndexTree = openvdb::UInt32Tree; // (first vertex << 3) | edge bits: 4 bytes a voxel
using IndexLeaf = IndexTree::LeafNodeType;

/// Value and active state of the voxel at local offset (x, y, z) + d of leaf, through the leaf
/// when it is inside and through the accessor otherwise.
inline bool probe(const FloatLeaf& leaf, FloatAccessor& acc, int x, int y, int z, int dx, int dy,
                  int dz, float& v)
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
constexpr uint8_t kBitCount[8] = {0, 1, 1, 2, 1, 2, 2, 3};

/// (OpenVDB maps multiply row vectors, p * M; below as M^T * p.)
struct Affine
{
    openvdb::Mat3d linear, jacobianInverse;
    openvdb::Vec3d translation;
    explicit Affine(const openvdb::math::Transform& xform)
    {
        const openvdb::math::AffineMap::Ptr map = xform.baseMap()->getAffineMap();
        const openvdb::Mat4d m = map->getMat4();
        linear = m.getMat3(), translation = m.getTranslation(),
        jacobianInverse = map->getConstJacobianInv();
    }
};

struct LeafMesh
{
    std::vector<std::array<uint32_t, 3>> triangles;
    std::vector<Vec3f> points, normals;
};

struct Passes
{
    const FloatTree& tree;
    Affine affine;
    IndexTree& index;
    openvdb::tree::LeafManager<IndexTree>& leaves;
    Context& ctx;
    std::vector<uint64_t> first; // per leaf: number of its first vertex (after pass 1)

    std::vector<LeafBits> bits; // per leaf (pass 0)
    std::unordered_map<const IndexLeaf*, size_t> position;
    const LeafBits none{};

    const FloatLeaf& valueLeaf(const IndexLeaf& leaf) const
    {
        return *tree.probeConstLeaf(leaf.origin());
    }

    /// The bits of the leaf one leaf away along +axis (or -axis: step -1); nothing active where
    /// there is no leaf.
    const LeafBits& next(const IndexLeaf& leaf, int axis, int step = 1) const
    {
        Coord o = leaf.origin();
        o[axis] += step * int(IndexLeaf::DIM);
        const IndexLeaf* n = index.probeConstLeaf(o);
        return n ? bits[position.at(n)] : none;
    }
    LeafStar star(const IndexLeaf& leaf) const
    {
        LeafStar s;
        s.values[0] = valueLeaf(leaf).buffer().data(), s.bits[0] = &bits[position.at(&leaf)];
        for (int a = 0; a < 3; ++a)
            for (int d = 0; d < 2; ++d) {
                Coord o = leaf.origin();
                o[a] += d ? int(FloatLeaf::DIM) : -int(FloatLeaf::DIM);
                if (const FloatLeaf* l = tree.probeConstLeaf(o))
                    s.values[1 + 2 * a + d] = l->buffer().data();
                s.bits[1 + 2 * a + d] = &next(leaf, a, d ? 1 : -1);
            }
        return s;
    }
    const FloatLeaf* nextValues(const IndexLeaf& leaf, int axis) const
    {
        Coord o = leaf.origin();
        o[axis] += int(IndexLeaf::DIM);
        return tree.probeConstLeaf(o);
    }

    // Pass 0: active and inside bits of every leaf.
    void readBits()
    {
        bits.resize(leaves.leafCount());
        for (size_t i = 0; i < leaves.leafCount(); ++i)
            position[&leaves.leaf(i)] = i;
        tbb::parallel_for(leaves.leafRange(),
                          [&](const openvdb::tree::LeafManager<IndexTree>::LeafRange& range) {
                              ctx.checkpoint();
                              for (auto leaf = range.begin(); leaf; ++leaf)
                                  bits[leaf.pos()] = LeafBits(valueLeaf(*leaf));
                          });
    }

    // Pass 1: crossing bits per active voxel, count per leaf.
    void markEdges()
    {
        std::vector<uint64_t> counts(leaves.leafCount(), 0);
        tbb::parallel_for(
            leaves.leafRange(), [&](const openvdb::tree::LeafManager<IndexTree>::LeafRange& range) {
                ctx.checkpoint();
                for (auto leaf = range.begin(); leaf; ++leaf) {
                    const LeafBits &here = bits[leaf.pos()], &nx = next(*leaf, 0),
                                   &ny = next(*leaf, 1), &nz = next(*leaf, 2);
                    uint64_t n = 0;
                    for (int x = 0; x < 8; ++x) {
                        const uint64_t act = here.active[x], in = here.in[x];
                        // Edges to +z, +y and +x with a sign change between active ends; at the
                        // leaf's far faces the other end is in the neighbouring leaf.
                        const uint64_t ez = ((in ^ in >> 1) & act & act >> 1 & ~kZ7) |
                                            ((in ^ nz.in[x] << 7) & act & nz.active[x] << 7 & kZ7);
                        const uint64_t ey =
                            ((in ^ in >> 8) & act & act >> 8 & kYBelow7) |
                            ((in ^ ny.in[x] << 56) & act & ny.active[x] << 56 & kY7);
                        const uint64_t ex = x < 7 ? (in ^ here.in[x + 1]) & act & here.active[x + 1]
                                                  : (in ^ nx.in[0]) & act & nx.active[0];
                        for (uint64_t todo = act; todo; todo &= todo - 1) {
                            const int b = __builtin_ctzll(todo);
                            const uint32_t edges = uint32_t(ex >> b & 1) |
                                                   uint32_t(ey >> b & 1) << 1 |
                                                   uint32_t(ez >> b & 1) << 2;
                            leaf->setValueOnly(openvdb::Index(x << 6 | b), edges);
                            n += kBitCount[edges];
                        }
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
        tbb::parallel_for(
            leaves.leafRange(), [&](const openvdb::tree::LeafManager<IndexTree>::LeafRange& range) {
                ctx.checkpoint();
                FloatAccessor acc(tree);
                for (auto leaf = range.begin(); leaf; ++leaf) {
                    const FloatLeaf& values = valueLeaf(*leaf);
                    const LeafStar star = this->star(*leaf);
                    const LeafBits& here = bits[leaf.pos()];
                    uint32_t* packed = leaf->buffer().data();
                    const float* buffer = values.buffer().data();
                    uint64_t next = first[leaf.pos()];
                    for (int x = 0; x < 8; ++x)
                        for (uint64_t todo = here.active[x]; todo; todo &= todo - 1) {
                            const int offset = x << 6 | __builtin_ctzll(todo);
                            const uint32_t edges = packed[offset];
                            if (!edges)
                                continue; // only voxels with crossing edges are ever looked up
                            packed[offset] = uint32_t(next) << 3 | edges;
                            const Coord l = FloatLeaf::offsetToLocalCoord(openvdb::Index(offset)),
                                        a = values.origin() + l;
                            const openvdb::Vec3d ga = star.gradient(l);
                            const float va = buffer[offset];
                            for (int axis = 0; axis < 3; ++axis) {
                                if (!(edges >> axis & 1)) continue;
                                Coord lb = l, b = a;
                                lb[axis] += 1, b[axis] += 1;
                                float vb = 0;
                                star.read(lb, axis, vb);
                                const double t = crossing(va, vb);
                                openvdb::Vec3d p = a.asVec3d();
                                p[axis] += t;
                                const openvdb::Vec3d w =
                                    affine.linear.transpose() * p + affine.translation;
                                const openvdb::Vec3d gb = lb[axis] < int(FloatLeaf::DIM)
                                                              ? star.gradient(lb)
                                                              : indexGradient(acc, b);
                                openvdb::Vec3d g = ga * (1 - t) + gb * t;
                                // Where the gradient vanishes: the edge direction, from inside to
                                // outside.
                                if (!(g.lengthSqr() > 0)) g[axis] = va < 0 ? 1.0 : -1.0;
                                g = affine.jacobianInverse.transpose() * g;
                                g.normalize();
                                mesh.points[next] = Vec3f(float(w.x()), float(w.y()), float(w.z()));
                                mesh.normals[next] =
                                    Vec3f(float(g.x()), float(g.y()), float(g.z()));
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
        tbb::parallel_for(
            leaves.leafRange(), [&](const openvdb::tree::LeafManager<IndexTree>::LeafRange& range) {
                ctx.checkpoint();
                FloatAccessor acc(tree);
                openvdb::tree::ValueAccessor<const IndexTree> idx(index);
                size_t cells = 0;
                for (auto leaf = range.begin(); leaf; ++leaf) {
                    const FloatLeaf& values = valueLeaf(*leaf);
                    auto& out = perLeaf[leaf.pos()];
                    const LeafBits &here = bits[leaf.pos()], &nx = next(*leaf, 0),
                                   &ny = next(*leaf, 1), &nz = next(*leaf, 2);
                    const float* buffer = values.buffer().data();
                    const float* plus[3] = {nullptr, nullptr,
                                            nullptr}; // neighbour buffers, read only when active
                    for (int a = 0; a < 3; ++a)
                        if (const FloatLeaf* l = nextValues(*leaf, a)) plus[a] = l->buffer().data();
                    float c[8];
                    // Value at local (x, y, z) with at most one coordinate equal to 8.
                    auto value = [&](int x, int y, int z) {
                        if (x == 8) return plus[0][y << 3 | z];
                        if (y == 8) return plus[1][x << 6 | z];
                        if (z == 8) return plus[2][x << 6 | y << 3];
                        return buffer[x << 6 | y << 3 | z];
                    };
                    // Cells that are complete and have a sign change, 64 candidates at a time, from
                    // the two x-planes of their corners (a, b: active; p, q: inside).
                    auto emit = [&](int x, uint64_t a0, uint64_t a1, uint64_t p0, uint64_t p1,
                                    uint64_t valid, int dy, int dz) {
                        const uint64_t complete = squareAll(a0) & squareAll(a1) & valid;
                        const uint64_t mixed =
                            (squareAny(p0) | squareAny(p1)) & ~(squareAll(p0) & squareAll(p1));
                        for (uint64_t todo = complete & mixed; todo; todo &= todo - 1) {
                            const int b = __builtin_ctzll(todo), y = (b >> 3) + dy,
                                      z = (b & 7) + dz;
                            for (int n = 0; n < 8; ++n)
                                c[n] =
                                    value(x + kCorner[n][0], y + kCorner[n][1], z + kCorner[n][2]);
                            ++cells;
                            cell(values.origin().offsetBy(x, y, z), c, *leaf, idx, mesh, out);
                        }
                    };
                    for (int x = 0; x < 7; ++x) {
                        emit(x, here.active[x], here.active[x + 1], here.in[x], here.in[x + 1],
                             ~kZ7 & kYBelow7, 0, 0);
                        // y = 7 (z < 7) and z = 7 (y < 7): one row / column of candidates each.
                        emit(x, acrossY(here.active[x], ny.active[x]),
                             acrossY(here.active[x + 1], ny.active[x + 1]),
                             acrossY(here.in[x], ny.in[x]), acrossY(here.in[x + 1], ny.in[x + 1]),
                             0x7F, 7, 0);
                        emit(x, acrossZ(here.active[x], nz.active[x]),
                             acrossZ(here.active[x + 1], nz.active[x + 1]),
                             acrossZ(here.in[x], nz.in[x]), acrossZ(here.in[x + 1], nz.in[x + 1]),
                             kZ0 & kYBelow7, 0, 7);
                    }
                    emit(7, here.active[7], nx.active[0], here.in[7], nx.in[0], ~kZ7 & kYBelow7, 0,
                         0); // x = 7
                    // Cells with two or three coordinates 7 (22 per leaf): through the accessor.
                    for (int k = 0; k < 22; ++k) {
                        const Coord l = k < 8    ? Coord(7, 7, k)
                                        : k < 15 ? Coord(7, k - 8, 7)
                                                 : Coord(k - 15, 7, 7);
                        const openvdb::Index offset = FloatLeaf::coordToOffset(l);
                        if (!values.isValueOn(offset)) continue;
                        c[0] = buffer[offset];
                        bool complete = true;
                        for (int n = 1; n < 8 && complete; ++n)
                            complete = probe(values, acc, l.x(), l.y(), l.z(), kCorner[n][0],
                                             kCorner[n][1], kCorner[n][2], c[n]);
                        if (!complete) continue;
                        int config = 0;
                        for (int n = 0; n < 8; ++n)
                            config |= int(inside(c[n])) << n;
                        if (config == 0 || config == 255) continue;
                        ++cells;
                        cell(values.origin() + l, c, *leaf, idx, mesh, out);
                    }
                }
                surfaceCells += cells;
            });
        return surfaceCells;
    }

    // The polygons of one cell (CellPolygons.h). A polygon is fanned from its first vertex,
    // except in a cell with an ambiguous face, where it gets a centre vertex instead.
    template <typename IndexAccessor>
    void cell(const Coord& origin, const float c[8], const IndexLeaf& indexLeaf, IndexAccessor& idx,
              const TriangleMesh& mesh, LeafMesh& out) const
    {
        const CellPolygons polygons(c);
        const int* next = polygons.next;
        const bool ambiguous = polygons.ambiguous;
        uint32_t vertex[12];
        for (int e = 0; e < 12; ++e) {
            if (next[e] < 0) continue;
            Coord g = origin;
            for (int a = 0; a < 3; ++a)
                g[a] += kCorner[kEdges.lowCorner[e]][a];
            const Coord l = g - indexLeaf.origin();
            const uint32_t packed =
                (unsigned(l.x()) | unsigned(l.y()) | unsigned(l.z())) < IndexLeaf::DIM
                    ? indexLeaf.getValue(IndexLeaf::coordToOffset(l))
                    : idx.getValue(g);
            const int axis = kEdges.axis[e];
            vertex[e] = uint32_t((packed >> 3) + kBitCount[packed & ((1 << axis) - 1)]);
        }
        polygons.forEach([&](const int* polygon, int n) {
            if (!ambiguous || n == 3) {
                for (int k = 1; k + 1 < n; ++k)
                    out.triangles.push_back(
                        {vertex[polygon[0]], vertex[polygon[k]], vertex[polygon[k + 1]]});
                return;
            }
            openvdb::Vec3d p(0.0), nrm(0.0);
            for (int k = 0; k < n; ++k) {
                const Vec3f &q = mesh.points[vertex[polygon[k]]],
                            &m = mesh.normals[vertex[polygon[k]]];
                p += openvdb::Vec3d(q.x, q.y, q.z) / n, nrm += openvdb::Vec3d(m.x, m.y, m.z);
            }
            if (nrm.lengthSqr() > 0) nrm.normalize();
            const uint32_t centre = kLocalVertex | uint32_t(out.points.size());
            out.points.push_back(Vec3f(float(p.x()), float(p.y()), float(p.z())));
            out.normals.push_back(Vec3f(float(nrm.x()), float(nrm.y()), float(nrm.z())));
            for (int k = 0; k < n; ++k)
                out.triangles.push_back({centre, vertex[polygon[k]], vertex[polygon[(k + 1) % n]]});
        });
    }
};

/// Drop vertices no triangle uses and renumber (order kept).
void dropUnusedVertices(TriangleMesh& mesh, Context& ctx)
{
    std::vector<uint32_t> map(mesh.points.size(), 0);
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t)
            map[v] = 1;
    uint32_t n = 0;
    for (size_t i = 0; i < map.size(); ++i) {
        if (!map[i]) continue;
        mesh.points[n] = mesh.points[i], mesh.normals[n] = mesh.normals[i];
        map[i] = n++;
    }
    mesh.points.resize(n), mesh.normals.resize(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.triangles.size(), 4096),
                      [&](const tbb::blocked_range<size_t>& r) {
                          ctx.checkpoint();
                          for (size_t i = r.begin(); i != r.end(); ++i)
                              for (uint32_t& v : mesh.triangles[i])
                                  v = map[v];
                      });
}

} // namespace

TriangleMesh marchingCubes(const openvdb::FloatGrid& grid, Context& ctx, size_t* surfaceCells)
{
    // Active tiles (rare in level sets) become voxels so that every active value is a leaf voxel.
    openvdb::FloatTree::Ptr voxelized;
    const FloatTree* tree = &grid.tree();
    if (tree->hasActiveTiles()) {
        voxelized = std::make_shared<FloatTree>(*tree);
        voxelized->voxelizeActiveTiles();
        tree = voxelized.get();
    }
    IndexTree index(*tree, uint32_t(0), openvdb::TopologyCopy());
    openvdb::tree::LeafManager<IndexTree> leaves(index);
    Passes passes{*tree, Affine(grid.transform()), index, leaves, ctx, {}, {}, {}};
    TriangleMesh mesh;
    passes.readBits();
    passes.markEdges();
    // a voxel's first vertex number must fit 29 bits beside its 3 edge bits (IndexTree)
    if (passes.first.back() >= (uint64_t(1) << 29))
        throw ValueError("the level set has more than 2^29 surface vertices; mesh it in parts");
    passes.placeVertices(mesh);
    std::vector<LeafMesh> perLeaf;
    const size_t cells = passes.triangulate(perLeaf, mesh);
    // The index tree (4 bytes a band voxel: 128 MB for a 1.7M-particle frame) and the leaf bits
    // are done with: free them before the join allocates the mesh's triangles.
    passes.bits = {}, passes.position = {};
    index.clear();
    // Join the leaves in order: centre vertices after the edge vertices; each leaf's pieces are
    // freed as they are copied.
    size_t triangles = 0, vertices = mesh.points.size();
    for (const LeafMesh& l : perLeaf)
        triangles += l.triangles.size(), vertices += l.points.size();
    if (vertices >= kLocalVertex)
        throw ValueError("the level set has more than 2^31 surface vertices; mesh it in parts");
    mesh.triangles.reserve(triangles);
    for (LeafMesh& l : perLeaf) {
        const uint32_t base = uint32_t(mesh.points.size());
        for (auto t : l.triangles) {
            for (uint32_t& v : t)
                if (v & kLocalVertex) v = base + (v & ~kLocalVertex);
            mesh.triangles.push_back(t);
        }
        mesh.points.insert(mesh.points.end(), l.points.begin(), l.points.end());
        mesh.normals.insert(mesh.normals.end(), l.normals.begin(), l.normals.end());
        l = LeafMesh();
    }
    dropUnusedVertices(mesh, ctx);
    if (surfaceCells) *surfaceCells = cells;
    return mesh;
}

} // namespace mesh
} // namespace fluidsurf
