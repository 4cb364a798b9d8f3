// MeshLevels.cc - marching cubes over the coarse cells at their own level, vertices keyed by
// the level-3 edge they lie on, then the cracks between levels closed (thesis §6.2.3-6.2.4).
//
// Keys. Every vertex is named by a level-3 edge (its lower point and axis), so cells of both
// levels find the vertex they share without a table per level (the thesis' two hash maps). A
// level-2 edge is two level-3 edges; its crossing takes the key of the half it lies on, judged
// by the sign of the middle value that level 3 sees there (midValue, Levels.h). Where level 3
// sees a sub-sampled middle, its crossing on that half is the same point, and is computed from
// the level-2 edge by both sides, so the shared vertex has one position.
//
// Cracks. On a face between a level-2 and a level-3 cell the outer crossings coincide; inside
// the face the level-3 side can bend through crossings of its own (Fig. 6.6). Each cell records
// the polygon edges it puts on such a face, by the level-2 face square they lie in. Per square,
// edges found in both directions cancel (the two sides agree there); the rest chain into loops
// (each side's edges run opposite ways around the gap). A loop with one level-2 edge has its
// level-3 points merged into that edge's ends (CollapseCracks.h), or where a merge would fold or
// pinch the mesh, the level-2 triangle is cut at them; any other loop is fanned with the
// opposite orientation. Every edge of the loop then has its second triangle: the mesh is closed.
#include "adaptive/CollapseCracks.h"
#include "adaptive/Levels.h"
#include "mesh/CellPolygons.h"
#include "post/Normals.h"

#include <fluidsurf/AdaptiveGrid.h>
#include <fluidsurf/Error.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <optional>
#include <tuple>

namespace fluidsurf {

namespace {

using adaptive::Coord;
using adaptive::kLevel2;
using adaptive::kLevel3;
using FloatTree = openvdb::FloatTree;
using FloatAccessor = openvdb::tree::ValueAccessor<const FloatTree>;

/// A vertex's name: a level-3 edge (lower point, axis 0-2), or for the centre vertex of a
/// polygon in a cell with an ambiguous face, the cell's lower point and 3 + the polygon's number.
struct Key
{
    int32_t x = 0, y = 0, z = 0, tag = 0;
    auto tie() const { return std::tie(x, y, z, tag); }
    bool operator<(const Key& o) const { return tie() < o.tie(); }
    bool operator==(const Key& o) const { return tie() == o.tie(); }
};
Key keyOf(const Coord& p, int tag)
{
    return {p.x(), p.y(), p.z(), tag};
}

struct VertexRecord
{
    Key key;
    Vec3f point;
};

/// A polygon edge on a face between levels, as the mesh holds it (from -> to), and the level-2
/// face square it lies in (its lower point, even, and the face's normal axis as tag).
struct Segment
{
    Key square, from, to;
    uint32_t block = 0, triangle = 0; // the triangle holding from -> to: block, number in it
    bool coarse = false;              // from a level-2 cell
};

/// A crack with one level-2 edge (a -> b, in triangle): its level-3 points, in order from a to b.
struct Split
{
    uint32_t block = 0, triangle = 0;
    Key a, b;
    std::vector<Key> between;
};

struct Block
{
    std::vector<uint32_t> corners;      // 3 per triangle: numbers in vertices
    std::vector<VertexRecord> vertices; // as the cells find them, then one per key (sorted)
    std::vector<uint32_t> global;       // the mesh's vertex number of each of vertices
    std::vector<Segment> segments;
    size_t cells[2] = {0, 0}, triangles[2] = {0, 0};

    /// One record per key, sorted by key, the corners renumbered to match: most vertices are
    /// found by several cells of the block.
    void mergeVertices()
    {
        std::vector<std::pair<Key, uint32_t>> order(vertices.size());
        for (uint32_t i = 0; i < order.size(); ++i)
            order[i] = {vertices[i].key, i};
        std::sort(order.begin(), order.end(),
                  [](const auto& a, const auto& b) { return a.first < b.first; });
        std::vector<uint32_t> renumber(vertices.size());
        std::vector<VertexRecord> unique;
        for (const auto& [key, i] : order) {
            if (unique.empty() || !(unique.back().key == key)) unique.push_back(vertices[i]);
            renumber[i] = uint32_t(unique.size() - 1);
        }
        for (uint32_t& c : corners)
            c = renumber[c];
        vertices = std::move(unique);
    }
};

constexpr size_t kCellsPerBlock = 128;

inline Coord offset(const Coord& p, int axis, int d)
{
    Coord q = p;
    q[axis] += d;
    return q;
}

struct CellMesher
{
    const AdaptiveGrid& grid;
    double dx; // level-3 voxel

    Vec3f world(const Coord& p, int axis, double t) const
    {
        double w[3] = {double(p.x()), double(p.y()), double(p.z())};
        w[axis] += t;
        return Vec3f(float(w[0] * dx), float(w[1] * dx), float(w[2] * dx));
    }

    /// The vertex of a level-2 edge from level-3 point p (even) along axis, end values a, b.
    /// Where level 3 holds the edge's middle and no level-3 cell touches it (a probe kept by
    /// LevelFields.h), the crossing is on the level-3 half-edge, as the uniform mesh of dx
    /// places it; else it is level 2's, as the level-3 cells on a transition compute it too.
    VertexRecord level2Vertex(const Coord& p, int axis, float a, float b,
                              adaptive::LevelLookup& levels, FloatAccessor& v3) const
    {
        const Coord middle = offset(p, axis, 1);
        float m = 0;
        if (v3.probeValue(middle, m) && !levels.touches(middle, kLevel3)) {
            const bool firstHalf = mesh::inside(a) != mesh::inside(m);
            return {keyOf(firstHalf ? p : middle, axis),
                    firstHalf ? world(p, axis, mesh::crossing(a, m))
                              : world(middle, axis, mesh::crossing(m, b))};
        }
        m = adaptive::midValue(a, b);
        const bool firstHalf = mesh::inside(a) != mesh::inside(m);
        return {keyOf(firstHalf ? p : middle, axis), world(p, axis, 2 * mesh::crossing(a, b))};
    }

    /// The values of the (n + 1)^3 lattice points from lo into value[z][y][x], NaN where a point
    /// is inactive: read from the (at most 8) leaves the points lie in, not point by point.
    static void gather(FloatAccessor& acc, const Coord& lo, int n, float (&value)[5][5][5])
    {
        using Leaf = FloatTree::LeafNodeType;
        constexpr float kNone = std::numeric_limits<float>::quiet_NaN();
        const Leaf* leaf[2][2][2];
        const Coord base(lo.x() & ~7, lo.y() & ~7, lo.z() & ~7);
        for (int k = 0; k < 8; ++k)
            leaf[k >> 2][k >> 1 & 1][k & 1] =
                acc.probeConstLeaf(base.offsetBy((k & 1) * 8, (k >> 1 & 1) * 8, (k >> 2) * 8));
        for (int z = 0; z <= n; ++z)
            for (int y = 0; y <= n; ++y)
                for (int x = 0; x <= n; ++x) {
                    const Coord p = lo.offsetBy(x, y, z);
                    const Leaf* l = leaf[(p.z() - base.z()) >> 3][(p.y() - base.y()) >> 3]
                                        [(p.x() - base.x()) >> 3];
                    float& v = value[z][y][x];
                    if (l) {
                        const openvdb::Index i = Leaf::coordToOffset(p);
                        v = l->isValueOn(i) ? l->getValue(i) : kNone;
                    } else if (!acc.probeValue(p, v)) { // a tile, or nothing
                        v = kNone;
                    }
                }
    }

    void cell(const Coord& coarse, int level, adaptive::LevelLookup& levels, FloatAccessor& v2,
              FloatAccessor& v3, uint32_t blockNumber, Block& out) const
    {
        const int n = level == kLevel3 ? 4 : 2, step = level == kLevel3 ? 1 : 2;
        const Coord origin(coarse.x() * 4, coarse.y() * 4, coarse.z() * 4);
        // Faces of the coarse cell that border the other level: -x, +x, -y, +y, -z, +z.
        bool transition[6];
        for (int f = 0; f < 6; ++f) {
            const int other = levels.level(offset(coarse, f / 2, f & 1 ? 1 : -1));
            transition[f] = other != 0 && other != level;
        }
        // The cell's lattice values (5^3 at level 3, 3^3 at level 2), read once for its 64 or 8
        // sub-cells; NaN where there is none.
        float value[5][5][5];
        if (level == kLevel3)
            gather(v3, origin, n, value);
        else
            gather(v2, Coord(coarse.x() * 2, coarse.y() * 2, coarse.z() * 2), n, value);
        int32_t slot[3][5][5][5]; // the vertex of each lattice edge: axis, lower point
        std::fill(&slot[0][0][0][0], &slot[0][0][0][0] + 3 * 125, -1);
        const size_t before = out.corners.size();
        for (int s = 0; s < n * n * n; ++s) {
            const int si[3] = {s % n, s / n % n, s / (n * n)};
            const Coord sub(origin.x() + step * si[0], origin.y() + step * si[1],
                            origin.z() + step * si[2]);
            float c[8];
            bool complete = true;
            for (int k = 0; k < 8 && complete; ++k) {
                c[k] = value[si[2] + mesh::kCorner[k][2]][si[1] + mesh::kCorner[k][1]]
                            [si[0] + mesh::kCorner[k][0]];
                complete = !std::isnan(c[k]);
            }
            if (!complete) continue;
            const int config = mesh::cellSignPattern(c);
            if (config == 0 || config == 255) continue;
            const mesh::CellPolygons polygons(c);
            uint32_t vertex[12]; // numbers in out.vertices
            for (int e = 0; e < 12; ++e) {
                if (polygons.next[e] < 0) continue;
                const int low = mesh::kEdges.lowCorner[e], axis = mesh::kEdges.axis[e];
                const Coord p(sub.x() + step * mesh::kCorner[low][0],
                              sub.y() + step * mesh::kCorner[low][1],
                              sub.z() + step * mesh::kCorner[low][2]);
                // The sub-cells share their edges: each edge's vertex is made once per cell.
                int32_t& known = slot[axis][si[2] + mesh::kCorner[low][2]]
                                     [si[1] + mesh::kCorner[low][1]][si[0] + mesh::kCorner[low][0]];
                if (known >= 0) {
                    vertex[e] = uint32_t(known);
                    continue;
                }
                const float a = c[low], b = c[low | 1 << axis];
                vertex[e] = uint32_t(out.vertices.size());
                known = int32_t(vertex[e]);
                out.vertices.push_back(level == kLevel2 ? level2Vertex(p, axis, a, b, levels, v3)
                                                        : level3Vertex(p, axis, a, b, levels, v2));
            }
            auto key = [&](int e) { return out.vertices[vertex[e]].key; };
            int number = 0;
            polygons.forEach([&](const int* edges, int count) {
                const uint32_t first = uint32_t(out.corners.size() / 3);
                const bool fan = !polygons.ambiguous || count == 3;
                if (fan) {
                    for (int k = 1; k + 1 < count; ++k)
                        out.corners.insert(out.corners.end(), {vertex[edges[0]], vertex[edges[k]],
                                                               vertex[edges[k + 1]]});
                } else {
                    Vec3d centre(0.0); // summed as the uniform mesher sums it
                    for (int k = 0; k < count; ++k)
                        centre += toVec3d(out.vertices[vertex[edges[k]]].point) / count;
                    const uint32_t mid = uint32_t(out.vertices.size());
                    out.vertices.push_back({keyOf(sub, 3 + number), toVec3f(centre)});
                    for (int k = 0; k < count; ++k)
                        out.corners.insert(out.corners.end(),
                                           {mid, vertex[edges[k]], vertex[edges[(k + 1) % count]]});
                }
                ++number;
                // Edges on a face between levels, for the cracks.
                for (int k = 0; k < count; ++k) {
                    const int e = edges[k], f = polygons.face[e], axis = f / 2;
                    if (!transition[f] || si[axis] != (f & 1 ? n - 1 : 0)) continue;
                    Coord square(sub.x() & ~1, sub.y() & ~1, sub.z() & ~1);
                    square[axis] = sub[axis] + (f & 1 ? step : 0);
                    // The triangle with polygon edge k -> k + 1: fans from vertex 0 hold it in
                    // triangle k - 1 (edge 0 -> 1 in 0, the last edge in count - 3); centre fans
                    // in triangle k.
                    const int t = !fan ? k : k == 0 ? 0 : k == count - 1 ? count - 3 : k - 1;
                    out.segments.push_back({keyOf(square, axis), key(e), key(polygons.next[e]),
                                            blockNumber, first + uint32_t(t), level == kLevel2});
                }
            });
        }
        const int l = level == kLevel3 ? 1 : 0;
        ++out.cells[l];
        out.triangles[l] += (out.corners.size() - before) / 3;
    }

    /// The vertex of level-3 edge p -> p + axis. On the line of a level-2 edge whose middle is
    /// sub-sampled it is that edge's crossing (see the top of the file).
    VertexRecord level3Vertex(const Coord& p, int axis, float a, float b,
                              adaptive::LevelLookup& levels, FloatAccessor& v2) const
    {
        const int other1 = (axis + 1) % 3, other2 = (axis + 2) % 3;
        if (!((p[other1] | p[other2]) & 1)) {
            const Coord even = offset(p, axis, -(p[axis] & 1)), middle = offset(even, axis, 1);
            if (levels.subsampled(middle)) {
                const Coord e2(even.x() >> 1, even.y() >> 1, even.z() >> 1);
                const float ea = v2.getValue(e2), eb = v2.getValue(offset(e2, axis, 1));
                return {keyOf(p, axis), world(even, axis, 2 * mesh::crossing(ea, eb))};
            }
        }
        return {keyOf(p, axis), world(p, axis, mesh::crossing(a, b))};
    }
};

/// The cracks of one face square: its edges chained into loops. A loop with one level-2 edge
/// becomes a Split (its level-3 points are merged into the edge's ends, or that edge's triangle
/// is cut at them: no sliver in the face plane, where the level-3 path can run straight along
/// the level-2 edge); any other loop is
/// fanned with the opposite orientation into patches. Returns false when the edges do not close
/// into loops.
bool closeSquare(std::vector<Segment>::const_iterator begin,
                 std::vector<Segment>::const_iterator end, std::vector<std::array<Key, 3>>& patches,
                 std::vector<Split>& splits)
{
    const size_t n = size_t(end - begin);
    // Edges both sides hold (in opposite directions) need nothing.
    std::vector<char> gone(n, 0);
    for (size_t i = 0; i < n; ++i)
        for (size_t j = i + 1; j < n && !gone[i]; ++j)
            if (!gone[j] && begin[i].from == begin[j].to && begin[i].to == begin[j].from)
                gone[i] = gone[j] = 1;
    bool closed = true;
    for (size_t start = 0; start < n; ++start) {
        if (gone[start]) continue;
        std::vector<size_t> loop;
        size_t e = start;
        while (true) {
            gone[e] = 1;
            loop.push_back(e);
            if (begin[e].to == begin[start].from) break;
            size_t next = n;
            for (size_t j = 0; j < n; ++j)
                if (!gone[j] && begin[j].from == begin[e].to) {
                    next = j;
                    break;
                }
            if (next == n) {
                closed = false;
                loop.clear();
                break;
            }
            e = next;
        }
        size_t coarse = 0, at = 0;
        for (size_t k = 0; k < loop.size(); ++k)
            if (begin[loop[k]].coarse) ++coarse, at = k;
        if (coarse == 1 && loop.size() >= 3) {
            const Segment& c = begin[loop[at]];
            Split split{c.block, c.triangle, c.from, c.to, {}};
            for (size_t k = loop.size() - 1; k > 1; --k)
                split.between.push_back(begin[loop[(at + k) % loop.size()]].from);
            splits.push_back(std::move(split));
            continue;
        }
        for (size_t k = 1; k + 1 < loop.size(); ++k)
            patches.push_back({begin[loop[0]].from, begin[loop[k + 1]].from, begin[loop[k]].from});
    }
    return closed;
}

} // namespace

TriangleMesh meshAdaptiveGrid(const AdaptiveGrid& grid, Context& ctx, AdaptiveMeshStats* stats,
                              const AdaptiveMeshOptions& options)
{
    const auto timer = ctx.scope("mesh");
    if (grid.empty() || !grid.level3 || !grid.levels)
        throw ValueError("meshAdaptiveGrid: the adaptive grid lacks a level");
    const double dx = grid.level3->voxelSize()[0];
    std::vector<std::pair<Coord, int>> cells;
    for (auto v = grid.levels->tree().cbeginValueOn(); v; ++v)
        if (*v == kLevel2 || *v == kLevel3) cells.emplace_back(v.getCoord(), *v);

    // Cells -> triangles (as keys), vertices, crack edges; in fixed blocks, so the order of
    // everything does not depend on the threads.
    std::vector<Block> blocks((cells.size() + kCellsPerBlock - 1) / kCellsPerBlock);
    const CellMesher mesher{grid, dx};
    std::optional<TimingTree::Scope> step; // the sub-stages, for -v
    step.emplace(ctx.timing(), "cells");
    tbb::parallel_for(size_t(0), blocks.size(), [&](size_t b) {
        ctx.checkpoint();
        adaptive::LevelLookup levels(grid.levels->tree());
        FloatAccessor v2(grid.level2->tree()), v3(grid.level3->tree());
        const size_t end = std::min(cells.size(), (b + 1) * kCellsPerBlock);
        for (size_t i = b * kCellsPerBlock; i < end; ++i)
            mesher.cell(cells[i].first, cells[i].second, levels, v2, v3, uint32_t(b), blocks[b]);
        blocks[b].mergeVertices();
    });

    step.emplace(ctx.timing(), "vertices and cracks");
    AdaptiveMeshStats s;
    std::vector<Segment> segments;
    size_t cornerCount = 0, records = 0;
    for (const Block& b : blocks) {
        segments.insert(segments.end(), b.segments.begin(), b.segments.end());
        cornerCount += b.corners.size(), records += b.vertices.size();
        s.level2Cells += b.cells[0], s.level3Cells += b.cells[1];
        s.level2Triangles += b.triangles[0], s.level3Triangles += b.triangles[1];
    }
    // One vertex per key (every record of a key carries the same point), numbered in key order;
    // each block learns the numbers of its own records.
    struct Tagged
    {
        const VertexRecord* record;
        uint32_t block, number;
    };
    std::vector<Tagged> tagged;
    tagged.reserve(records);
    for (size_t b = 0; b < blocks.size(); ++b) {
        blocks[b].global.resize(blocks[b].vertices.size());
        for (size_t i = 0; i < blocks[b].vertices.size(); ++i)
            tagged.push_back({&blocks[b].vertices[i], uint32_t(b), uint32_t(i)});
    }
    tbb::parallel_sort(tagged.begin(), tagged.end(), [](const Tagged& a, const Tagged& b) {
        return a.record->key < b.record->key;
    });
    std::vector<VertexRecord> vertices;
    for (const Tagged& t : tagged) {
        if (vertices.empty() || !(vertices.back().key == t.record->key))
            vertices.push_back(*t.record);
        blocks[t.block].global[t.number] = uint32_t(vertices.size() - 1);
    }
    if (vertices.size() >= (size_t(1) << 32))
        throw ValueError("the adaptive grid has more than 2^32 surface vertices");
    // The crack vertices, by key.
    auto indexOf = [&](const Key& k) {
        return uint32_t(
            std::lower_bound(vertices.begin(), vertices.end(), k,
                             [](const VertexRecord& v, const Key& key) { return v.key < key; }) -
            vertices.begin());
    };

    // Cracks, square by square.
    tbb::parallel_sort(segments.begin(), segments.end(), [](const Segment& a, const Segment& b) {
        return std::tie(a.square, a.from, a.to) < std::tie(b.square, b.from, b.to);
    });
    std::vector<size_t> squareStart;
    for (size_t i = 0; i < segments.size(); ++i)
        if (i == 0 || !(segments[i].square == segments[i - 1].square)) squareStart.push_back(i);
    squareStart.push_back(segments.size());
    const size_t squares = squareStart.size() - 1;
    std::vector<std::vector<std::array<Key, 3>>> patches(squares);
    std::vector<std::vector<Split>> splits(squares);
    std::vector<char> open(squares, 0);
    tbb::parallel_for(size_t(0), squares, [&](size_t q) {
        open[q] = !closeSquare(segments.begin() + squareStart[q],
                               segments.begin() + squareStart[q + 1], patches[q], splits[q]);
    });

    step.emplace(ctx.timing(), "triangles");
    TriangleMesh mesh;
    mesh.points.resize(vertices.size());
    for (size_t i = 0; i < vertices.size(); ++i)
        mesh.points[i] = vertices[i].point;
    mesh.triangles.resize(cornerCount / 3);
    std::vector<size_t> first(blocks.size() + 1, 0);
    for (size_t b = 0; b < blocks.size(); ++b)
        first[b + 1] = first[b] + blocks[b].corners.size() / 3;
    {
        tbb::parallel_for(size_t(0), blocks.size(), [&](size_t b) {
            const std::vector<uint32_t>& k = blocks[b].corners;
            const std::vector<uint32_t>& g = blocks[b].global;
            for (size_t t = 0; t < k.size() / 3; ++t)
                mesh.triangles[first[b] + t] = {g[k[3 * t]], g[k[3 * t + 1]], g[k[3 * t + 2]]};
        });
    }
    // Cracks with one level-2 edge: their level-3 points merge into the edge's ends where they
    // can (CollapseCracks.h); the rest cut the level-2 triangle, below.
    std::vector<adaptive::CrackPath> paths;
    std::vector<size_t> cutTriangle;
    for (size_t q = 0; q < squares; ++q)
        for (const Split& sp : splits[q]) {
            adaptive::CrackPath path{indexOf(sp.a), indexOf(sp.b), {}};
            for (const Key& k : sp.between)
                path.between.push_back(indexOf(k));
            paths.push_back(std::move(path));
            cutTriangle.push_back(first[sp.block] + sp.triangle);
        }
    std::vector<char> removed;
    if (options.mergeCrackPoints)
        s.mergedCrackPoints = adaptive::collapseCracks(mesh, paths, removed);
    // Splits: a triangle cut by cracks is fanned from the corner opposite each cut edge through
    // the crack's level-3 points, one cut after the other (a level-2 cell's corner triangle can
    // be cut on two edges, by two level-3 faces).
    const size_t before = mesh.triangles.size();
    {
        std::vector<std::pair<size_t, const adaptive::CrackPath*>> cut;
        for (size_t i = 0; i < paths.size(); ++i)
            if (!paths[i].between.empty()) cut.emplace_back(cutTriangle[i], &paths[i]);
        std::stable_sort(cut.begin(), cut.end(),
                         [](const auto& a, const auto& b) { return a.first < b.first; });
        std::vector<std::array<uint32_t, 3>> pieces;
        for (size_t i = 0; i < cut.size();) {
            const size_t tri = cut[i].first;
            pieces.assign(1, mesh.triangles[tri]);
            for (; i < cut.size() && cut[i].first == tri; ++i) {
                const adaptive::CrackPath& sp = *cut[i].second;
                const uint32_t a = sp.a, b = sp.b;
                size_t piece = 0;
                int k = 3;
                for (; piece < pieces.size() && k == 3; ++piece)
                    for (k = 0; k < 3; ++k)
                        if (pieces[piece][k] == a && pieces[piece][(k + 1) % 3] == b) break;
                if (k == 3) { // no triangle holds the edge (never seen): the crack stays open
                    ++s.openCracks;
                    continue;
                }
                --piece;
                const uint32_t c = pieces[piece][(k + 2) % 3];
                uint32_t prev = a;
                for (size_t j = 0; j <= sp.between.size(); ++j) {
                    const uint32_t next = j < sp.between.size() ? sp.between[j] : b;
                    const std::array<uint32_t, 3> t{prev, next, c};
                    if (j == 0)
                        pieces[piece] = t;
                    else
                        pieces.push_back(t);
                    prev = next;
                }
            }
            mesh.triangles[tri] = pieces[0];
            mesh.triangles.insert(mesh.triangles.end(), pieces.begin() + 1, pieces.end());
        }
    }
    for (size_t q = 0; q < squares; ++q) {
        s.openCracks += open[q];
        for (const auto& t : patches[q])
            mesh.triangles.push_back({indexOf(t[0]), indexOf(t[1]), indexOf(t[2])});
    }
    s.patchTriangles = mesh.triangles.size() - before;
    // The level-3 triangles the merges flattened (all made by the cells, before the cuts).
    size_t kept = 0;
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        if (t >= removed.size() || !removed[t]) mesh.triangles[kept++] = mesh.triangles[t];
    s.level3Triangles -= mesh.triangles.size() - kept;
    mesh.triangles.resize(kept);
    if (s.mergedCrackPoints > 0) { // the merged points are in no triangle: drop them, in order
        std::vector<uint32_t> renumber(mesh.points.size(), 0);
        for (const auto& t : mesh.triangles)
            for (uint32_t v : t)
                renumber[v] = 1;
        uint32_t used = 0;
        for (size_t i = 0; i < mesh.points.size(); ++i)
            if (renumber[i]) mesh.points[used] = mesh.points[i], renumber[i] = used++;
        mesh.points.resize(used);
        for (auto& t : mesh.triangles)
            for (uint32_t& v : t)
                v = renumber[v];
    }
    step.emplace(ctx.timing(), "normals");
    post::computeAngleWeightedNormals(mesh);
    if (stats) *stats = s;
    return mesh;
}

} // namespace fluidsurf
