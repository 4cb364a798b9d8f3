// MarchingCubes.cc - marching cubes over the active band (see MarchingCubes.h for the passes).
#include "mesh/MarchingCubes.h"

#include "mesh/CellPolygons.h"
#include "mesh/Gradient.h"
#include "mesh/LeafBits.h"
#include "mesh/LeafTable.h"
#include "util/BitCount.h"
#include "util/Memory.h"

#include <fluidsurf/Error.h>

#include <openvdb/tree/LeafManager.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <functional>
#include <numeric>

namespace fluidsurf {
namespace mesh {

namespace {

using openvdb::Coord;
using FloatTree = openvdb::FloatTree;
using FloatLeaf = FloatTree::LeafNodeType;
using Leaves = openvdb::tree::LeafManager<const FloatTree>;
using LeafRange = Leaves::LeafRange;

/// A leaf's crossing edges: per axis, the voxels whose edge to +axis (to an active neighbour)
/// changes sign, as 8 words of 64 bits (LeafBits' order); and per word, the edges in the words
/// before it. The vertices are numbered leaf by leaf, voxel by voxel in offset order, and +x,
/// +y, +z within a voxel, so a vertex's number is a prefix count of these bits: 224 bytes a
/// leaf instead of a 4-byte number per band voxel (an index tree: 128 MB on a 1.7M-particle
/// frame).
struct EdgeWords
{
    // (no initialisers: markEdges writes every word of every leaf's, on all threads)
    uint64_t axis[3][8];
    uint32_t before[8];

    /// The number, from the leaf's first vertex, of the vertex on the edge from local offset i
    /// to +axis (which must cross).
    uint32_t vertex(unsigned i, int axis) const
    {
        const unsigned w = i >> 6;
        const uint64_t below = (uint64_t(1) << (i & 63)) - 1;
        uint32_t n = before[w] + util::bitCount3(this->axis[0][w] & below, this->axis[1][w] & below,
                                                 this->axis[2][w] & below);
        for (int a = 0; a < axis; ++a)
            n += uint32_t(this->axis[a][w] >> (i & 63) & 1);
        return n;
    }
};

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

/// Where a leaf's cells go: counted (pass 2), then written at the leaf's place in the mesh
/// (pass 4). Triangulated into per-leaf pieces and joined after, the pieces and the mesh were
/// both resident at the stage's peak (46 MB of pieces on the 1.7M-particle frame).
struct CellCount
{
    static constexpr bool kWrites = false;
    size_t triangles = 0, centres = 0;
    void triangle(uint32_t, uint32_t, uint32_t) { ++triangles; }
    void add(size_t fanned) { triangles += fanned; }
    uint32_t centre(const Vec3f&, const Vec3f&) { return uint32_t(centres++); }
};
struct CellWriter
{
    static constexpr bool kWrites = true;
    TriangleMesh& mesh;
    size_t nextTriangle;
    uint32_t nextCentre;
    void triangle(uint32_t a, uint32_t b, uint32_t c)
    {
        mesh.triangles[nextTriangle++] = {a, b, c};
    }
    uint32_t centre(const Vec3f& p, const Vec3f& n)
    {
        mesh.points[nextCentre] = p;
        if (!mesh.normals.empty()) mesh.normals[nextCentre] = n;
        return nextCentre++;
    }
};

struct Passes
{
    const FloatTree& tree;
    Affine affine;
    Leaves& leaves;
    Context& ctx;
    std::vector<uint64_t> first; // per leaf: number of its first vertex (after pass 1)
    /// per leaf (after pass 2): where its triangles go, and its centre vertices (from the
    /// first after the edge vertices)
    std::vector<uint64_t> triangleStart, centreStart;

    std::vector<LeafBits> bits;          // per leaf (pass 0)
    util::NoInitVector<EdgeWords> edges; // per leaf (pass 1)
    LeafTable table{leaves};
    const LeafBits none{};

    /// The position of the leaf at origin o, or -1 where there is none.
    long leafAt(const Coord& o) const { return table.find(o); }

    /// The bits of the leaf one leaf away along +axis (or -axis: step -1); nothing active where
    /// there is no leaf.
    const LeafBits& next(const FloatLeaf& leaf, int axis, int step = 1) const
    {
        Coord o = leaf.origin();
        o[axis] += step * int(FloatLeaf::DIM);
        const long n = leafAt(o);
        return n >= 0 ? bits[size_t(n)] : none;
    }
    /// leaf, at position pos, and its six face neighbours.
    LeafStar star(const FloatLeaf& leaf, size_t pos) const
    {
        LeafStar s;
        s.values[0] = leaf.buffer().data(), s.bits[0] = &bits[pos];
        for (int a = 0; a < 3; ++a)
            for (int d = 0; d < 2; ++d) {
                Coord o = leaf.origin();
                o[a] += d ? int(FloatLeaf::DIM) : -int(FloatLeaf::DIM);
                const long n = leafAt(o);
                if (n >= 0) s.values[1 + 2 * a + d] = leaves.leaf(size_t(n)).buffer().data();
                s.bits[1 + 2 * a + d] = n >= 0 ? &bits[size_t(n)] : &none;
            }
        return s;
    }
    const FloatLeaf* nextValues(const FloatLeaf& leaf, int axis) const
    {
        Coord o = leaf.origin();
        o[axis] += int(FloatLeaf::DIM);
        const long n = leafAt(o);
        return n >= 0 ? &leaves.leaf(size_t(n)) : nullptr;
    }

    // Pass 0: active and inside bits of every leaf.
    void readBits()
    {
        bits.resize(leaves.leafCount());
        tbb::parallel_for(leaves.leafRange(), [&](const LeafRange& range) {
            ctx.checkpoint();
            for (auto leaf = range.begin(); leaf; ++leaf)
                bits[leaf.pos()] = LeafBits(*leaf);
        });
    }

    // Pass 1: crossing edges per leaf, counted.
    void markEdges()
    {
        std::vector<uint64_t> counts(leaves.leafCount(), 0);
        edges.resize(leaves.leafCount()); // (each leaf's written below)
        tbb::parallel_for(leaves.leafRange(), [&](const LeafRange& range) {
            ctx.checkpoint();
            for (auto leaf = range.begin(); leaf; ++leaf) {
                const LeafBits &here = bits[leaf.pos()], &nx = next(*leaf, 0), &ny = next(*leaf, 1),
                               &nz = next(*leaf, 2);
                EdgeWords& e = edges[leaf.pos()];
                uint32_t n = 0;
                for (int x = 0; x < 8; ++x) {
                    const uint64_t act = here.active[x], in = here.in[x];
                    // Edges to +z, +y and +x with a sign change between active ends; at the
                    // leaf's far faces the other end is in the neighbouring leaf.
                    const uint64_t ez = ((in ^ in >> 1) & act & act >> 1 & ~kZ7) |
                                        ((in ^ nz.in[x] << 7) & act & nz.active[x] << 7 & kZ7);
                    const uint64_t ey = ((in ^ in >> 8) & act & act >> 8 & kYBelow7) |
                                        ((in ^ ny.in[x] << 56) & act & ny.active[x] << 56 & kY7);
                    const uint64_t ex = x < 7 ? (in ^ here.in[x + 1]) & act & here.active[x + 1]
                                              : (in ^ nx.in[0]) & act & nx.active[0];
                    e.axis[0][x] = ex, e.axis[1][x] = ey, e.axis[2][x] = ez;
                    e.before[x] = n;
                    n += util::bitCount3(ex, ey, ez);
                }
                counts[leaf.pos()] = n;
            }
        });
        first.assign(counts.size() + 1, 0);
        std::partial_sum(counts.begin(), counts.end(), first.begin() + 1);
    }

    // Pass 3: positions and normals of the edge vertices, in their numbers' order (mesh.points,
    // and mesh.normals if wanted, are sized for the centre vertices too).
    void placeVertices(TriangleMesh& mesh)
    {
        const bool normals = !mesh.normals.empty();
        tbb::parallel_for(leaves.leafRange(), [&](const LeafRange& range) {
            ctx.checkpoint();
            FloatAccessor acc(tree);
            for (auto leaf = range.begin(); leaf; ++leaf) {
                const FloatLeaf& values = *leaf;
                const LeafStar star = this->star(*leaf, leaf.pos());
                const EdgeWords& e = this->edges[leaf.pos()];
                const float* buffer = values.buffer().data();
                uint64_t next = first[leaf.pos()];
                for (int x = 0; x < 8; ++x)
                    for (uint64_t todo = e.axis[0][x] | e.axis[1][x] | e.axis[2][x]; todo;
                         todo &= todo - 1) {
                        const int b = __builtin_ctzll(todo), offset = x << 6 | b;
                        const uint32_t edges = uint32_t(e.axis[0][x] >> b & 1) |
                                               uint32_t(e.axis[1][x] >> b & 1) << 1 |
                                               uint32_t(e.axis[2][x] >> b & 1) << 2;
                        const Coord l = FloatLeaf::offsetToLocalCoord(openvdb::Index(offset)),
                                    a = values.origin() + l;
                        const openvdb::Vec3d ga = normals ? star.gradient(l) : openvdb::Vec3d(0.0);
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
                            mesh.points[next] = Vec3f(float(w.x()), float(w.y()), float(w.z()));
                            if (!normals) {
                                ++next;
                                continue;
                            }
                            const openvdb::Vec3d gb = lb[axis] < int(FloatLeaf::DIM)
                                                          ? star.gradient(lb)
                                                          : indexGradient(acc, b);
                            openvdb::Vec3d g = ga * (1 - t) + gb * t;
                            // Where the gradient vanishes: the edge direction, from inside to
                            // outside.
                            if (!(g.lengthSqr() > 0)) g[axis] = va < 0 ? 1.0 : -1.0;
                            g = affine.jacobianInverse.transpose() * g;
                            g.normalize();
                            mesh.normals[next] = Vec3f(float(g.x()), float(g.y()), float(g.z()));
                            ++next;
                        }
                    }
            }
        });
    }

    // The cells of one leaf (at position pos) that are complete and have a sign change, into
    // out (CellCount or CellWriter); returns how many.
    template <typename Sink>
    size_t cellsOf(const FloatLeaf& leaf, size_t pos, FloatAccessor& acc, const TriangleMesh& mesh,
                   Sink& out) const
    {
        size_t cells = 0;
        const VertexStar idx = Sink::kWrites ? vertexStar(leaf, pos) : VertexStar();
        const LeafBits &here = bits[pos], &nx = next(leaf, 0), &ny = next(leaf, 1),
                       &nz = next(leaf, 2);
        const float* buffer = leaf.buffer().data();
        const float* plus[3] = {nullptr, nullptr,
                                nullptr}; // neighbour buffers, read only when active
        for (int a = 0; a < 3; ++a)
            if (const FloatLeaf* l = nextValues(leaf, a)) plus[a] = l->buffer().data();
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
        auto emit = [&](int x, uint64_t a0, uint64_t a1, uint64_t p0, uint64_t p1, uint64_t valid,
                        int dy, int dz) {
            const uint64_t complete = squareAll(a0) & squareAll(a1) & valid;
            const uint64_t mixed =
                (squareAny(p0) | squareAny(p1)) & ~(squareAll(p0) & squareAll(p1));
            for (uint64_t todo = complete & mixed; todo; todo &= todo - 1) {
                const int b = __builtin_ctzll(todo), y = (b >> 3) + dy, z = (b & 7) + dz;
                for (int n = 0; n < 8; ++n)
                    c[n] = value(x + kCorner[n][0], y + kCorner[n][1], z + kCorner[n][2]);
                ++cells;
                cell(leaf.origin().offsetBy(x, y, z), c, idx, mesh, out);
            }
        };
        for (int x = 0; x < 7; ++x) {
            emit(x, here.active[x], here.active[x + 1], here.in[x], here.in[x + 1], ~kZ7 & kYBelow7,
                 0, 0);
            // y = 7 (z < 7) and z = 7 (y < 7): one row / column of candidates each.
            emit(x, acrossY(here.active[x], ny.active[x]),
                 acrossY(here.active[x + 1], ny.active[x + 1]), acrossY(here.in[x], ny.in[x]),
                 acrossY(here.in[x + 1], ny.in[x + 1]), 0x7F, 7, 0);
            emit(x, acrossZ(here.active[x], nz.active[x]),
                 acrossZ(here.active[x + 1], nz.active[x + 1]), acrossZ(here.in[x], nz.in[x]),
                 acrossZ(here.in[x + 1], nz.in[x + 1]), kZ0 & kYBelow7, 0, 7);
        }
        emit(7, here.active[7], nx.active[0], here.in[7], nx.in[0], ~kZ7 & kYBelow7, 0,
             0); // x = 7
        // Cells with two or three coordinates 7 (22 per leaf): through the accessor.
        for (int k = 0; k < 22; ++k) {
            const Coord l = k < 8    ? Coord(7, 7, k)
                            : k < 15 ? Coord(7, k - 8, 7)
                                     : Coord(k - 15, 7, 7);
            const openvdb::Index offset = FloatLeaf::coordToOffset(l);
            if (!leaf.isValueOn(offset)) continue;
            c[0] = buffer[offset];
            bool complete = true;
            for (int n = 1; n < 8 && complete; ++n)
                complete = probe(leaf, acc, l.x(), l.y(), l.z(), kCorner[n][0], kCorner[n][1],
                                 kCorner[n][2], c[n]);
            if (!complete) continue;
            const int config = cellSignPattern(c);
            if (config == 0 || config == 255) continue;
            ++cells;
            cell(leaf.origin() + l, c, idx, mesh, out);
        }
        return cells;
    }

    // Pass 2: per leaf, the triangles and centre vertices of its cells, counted, and where
    // they go; returns the number of cells.
    size_t countCells()
    {
        const size_t n = leaves.leafCount();
        std::vector<uint64_t> triangles(n, 0), centres(n, 0);
        std::atomic<size_t> surfaceCells{0};
        const TriangleMesh none;
        tbb::parallel_for(leaves.leafRange(), [&](const LeafRange& range) {
            ctx.checkpoint();
            FloatAccessor acc(tree);
            size_t cells = 0;
            for (auto leaf = range.begin(); leaf; ++leaf) {
                CellCount count;
                cells += cellsOf(*leaf, leaf.pos(), acc, none, count);
                triangles[leaf.pos()] = count.triangles, centres[leaf.pos()] = count.centres;
            }
            surfaceCells += cells;
        });
        triangleStart.assign(n + 1, 0);
        centreStart.assign(n + 1, 0);
        std::partial_sum(triangles.begin(), triangles.end(), triangleStart.begin() + 1);
        std::partial_sum(centres.begin(), centres.end(), centreStart.begin() + 1);
        return surfaceCells;
    }

    // Pass 4: the triangles of every complete cell with a sign change, and the centre vertices
    // of cells with an ambiguous face, each leaf's where pass 2 put them.
    void triangulate(TriangleMesh& mesh)
    {
        tbb::parallel_for(leaves.leafRange(), [&](const LeafRange& range) {
            ctx.checkpoint();
            FloatAccessor acc(tree);
            for (auto leaf = range.begin(); leaf; ++leaf) {
                CellWriter out{mesh, triangleStart[leaf.pos()],
                               uint32_t(first.back() + centreStart[leaf.pos()])};
                cellsOf(*leaf, leaf.pos(), acc, mesh, out);
            }
        });
    }

    /// A leaf and the 7 leaves beyond its +x, +y, +z faces, edges and corner: where a cell's
    /// edges may start. Indexed by (x >= 8) | (y >= 8) << 1 | (z >= 8) << 2 of a local coord.
    struct VertexStar
    {
        Coord origin;
        const EdgeWords* edges[8] = {};
        uint64_t first[8] = {};

        uint32_t vertex(Coord l, int axis) const
        {
            const int k = (l.x() >> 3) | (l.y() >> 3) << 1 | (l.z() >> 3) << 2;
            return uint32_t(first[k]) +
                   edges[k]->vertex(unsigned((l.x() & 7) << 6 | (l.y() & 7) << 3 | (l.z() & 7)),
                                    axis);
        }
    };
    VertexStar vertexStar(const FloatLeaf& leaf, size_t pos) const
    {
        VertexStar s;
        s.origin = leaf.origin();
        for (int k = 0; k < 8; ++k) {
            const long n =
                k ? leafAt(s.origin.offsetBy((k & 1) * 8, (k >> 1 & 1) * 8, (k >> 2 & 1) * 8))
                  : long(pos);
            if (n >= 0) s.edges[k] = &edges[size_t(n)], s.first[k] = first[size_t(n)];
        }
        return s;
    }

    /// The vertex on cell edge e of the cell at origin (its crossing edges start in its leaf or
    /// in a leaf of idx).
    static uint32_t edgeVertex(const Coord& origin, const VertexStar& idx, int e)
    {
        Coord g = origin;
        for (int a = 0; a < 3; ++a)
            g[a] += kCorner[kEdges.lowCorner[e]][a];
        return idx.vertex(g - idx.origin, kEdges.axis[e]);
    }

    // The polygons of one cell (CellPolygons.h). A polygon is fanned from its first vertex,
    // except in a cell with an ambiguous face, where it gets a centre vertex instead. The
    // cell's crossing edges start in its leaf or in a leaf of idx (both ends are active).
    template <typename Sink>
    void cell(const Coord& origin, const float c[8], const VertexStar& idx,
              const TriangleMesh& mesh, Sink& out) const
    {
        if constexpr (!Sink::kWrites) { // counting: the signs alone, as a rule
            if (const int n = cellTriangles(c); n >= 0) return out.add(size_t(n));
        } else if (const CellFan fan = cellFan(c); fan.polygons) {
            // the signs decide: the table's triangles, without walking the polygons
            uint32_t vertex[12];
            for (int e = 0; e < 12; ++e)
                if (fan.polygons->next[e] >= 0) vertex[e] = edgeVertex(origin, idx, e);
            for (int t = 0; t < fan.count; ++t)
                out.triangle(vertex[fan.triangles[t][0]], vertex[fan.triangles[t][1]],
                             vertex[fan.triangles[t][2]]);
            return;
        }
        const CellPolygons polygons(c);
        const int* next = polygons.next;
        const bool ambiguous = polygons.ambiguous;
        uint32_t vertex[12] = {};
        if constexpr (Sink::kWrites)
            for (int e = 0; e < 12; ++e)
                if (next[e] >= 0) vertex[e] = edgeVertex(origin, idx, e);
        polygons.forEach([&](const int* polygon, int n) {
            if (!ambiguous || n == 3) {
                for (int k = 1; k + 1 < n; ++k)
                    out.triangle(vertex[polygon[0]], vertex[polygon[k]], vertex[polygon[k + 1]]);
                return;
            }
            openvdb::Vec3d p(0.0), nrm(0.0);
            if constexpr (Sink::kWrites) {
                const bool normals = !mesh.normals.empty();
                for (int k = 0; k < n; ++k) {
                    const Vec3f& q = mesh.points[vertex[polygon[k]]];
                    p += openvdb::Vec3d(q.x, q.y, q.z) / n;
                    if (normals) {
                        const Vec3f& m = mesh.normals[vertex[polygon[k]]];
                        nrm += openvdb::Vec3d(m.x, m.y, m.z);
                    }
                }
                if (nrm.lengthSqr() > 0) nrm.normalize();
            }
            const uint32_t centre =
                out.centre(Vec3f(float(p.x()), float(p.y()), float(p.z())),
                           Vec3f(float(nrm.x()), float(nrm.y()), float(nrm.z())));
            for (int k = 0; k < n; ++k)
                out.triangle(centre, vertex[polygon[k]], vertex[polygon[(k + 1) % n]]);
        });
    }
};

} // namespace

Affine::Affine(const openvdb::math::Transform& xform)
{
    const openvdb::math::AffineMap::Ptr map = xform.baseMap()->getAffineMap();
    const openvdb::Mat4d m = map->getMat4();
    linear = m.getMat3(), translation = m.getTranslation(),
    jacobianInverse = map->getConstJacobianInv();
}

void checkVertexCount(uint64_t vertices)
{
    // Vertex numbers are 32 bits; the meshes here stay under 2^31 vertices.
    if (vertices >= 0x80000000u)
        throw ValueError("the level set has more than 2^31 surface vertices; mesh it in parts");
}

// As a rule no vertex is unused (band completion closes every cell around a crossing edge), and
// the marks and their count, on all threads, are then all there is to it: serially they were 4%
// of marching cubes on two cores (14 ms of the 13.1M drop's 0.34 s), and more of it on sixteen.
void dropUnusedVertices(TriangleMesh& mesh, Context& ctx)
{
    util::NoInitVector<uint32_t> map(mesh.points.size()); // (zeroed on all threads)
    util::fillInParallel(map, 0u);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.triangles.size(), 4096),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i)
                              for (uint32_t v : mesh.triangles[i]) // a mark: any order, any repeat
                                  __atomic_store_n(&map[v], 1u, __ATOMIC_RELAXED);
                      });
    const size_t used = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, map.size(), 4096), size_t(0),
        [&](const tbb::blocked_range<size_t>& r, size_t sum) {
            for (size_t i = r.begin(); i != r.end(); ++i)
                sum += map[i];
            return sum;
        },
        std::plus<size_t>());
    if (used == map.size()) return;
    uint32_t n = 0;
    for (size_t i = 0; i < map.size(); ++i) {
        if (!map[i]) continue;
        mesh.points[n] = mesh.points[i];
        if (!mesh.normals.empty()) mesh.normals[n] = mesh.normals[i];
        map[i] = n++;
    }
    mesh.points.resize(n);
    if (!mesh.normals.empty()) mesh.normals.resize(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.triangles.size(), 4096),
                      [&](const tbb::blocked_range<size_t>& r) {
                          ctx.checkpoint();
                          for (size_t i = r.begin(); i != r.end(); ++i)
                              for (uint32_t& v : mesh.triangles[i])
                                  v = map[v];
                      });
}

TriangleMesh marchingCubes(const openvdb::FloatGrid& grid, Context& ctx, size_t* surfaceCells,
                           RawNormals normals)
{
    // Active tiles' faces become voxels so that every value the mesh needs is a leaf voxel.
    openvdb::FloatTree::Ptr voxelized;
    const FloatTree* tree = &leafOnlyTree(grid, voxelized, ctx);
    Leaves leaves(*tree);
    Passes passes{*tree, Affine(grid.transform()), leaves, ctx, {}, {}, {}, {}, {}};
    TriangleMesh mesh;
    passes.readBits();
    passes.markEdges();
    const size_t cells = passes.countCells();
    // the centre vertices come after the edge vertices
    const uint64_t vertices = passes.first.back() + passes.centreStart.back();
    checkVertexCount(vertices);
    util::resizeInParallel(mesh.points, vertices);
    if (normals == RawNormals::Gradient) util::resizeInParallel(mesh.normals, vertices);
    passes.placeVertices(mesh);
    util::resizeInParallel(mesh.triangles, passes.triangleStart.back());
    passes.triangulate(mesh);
    // (`= {}` would keep their capacity: it is the initializer-list assignment)
    std::vector<LeafBits>().swap(passes.bits);
    util::NoInitVector<EdgeWords>().swap(passes.edges);
    dropUnusedVertices(mesh, ctx);
    if (surfaceCells) *surfaceCells = cells;
    return mesh;
}

} // namespace mesh
} // namespace fluidsurf
