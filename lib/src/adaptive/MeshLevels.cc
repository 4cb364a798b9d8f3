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
// (each side's edges run opposite ways around the gap), and each loop is fanned with the
// opposite orientation. Every edge of the loop then has its second triangle: the mesh is closed.
#include "adaptive/Levels.h"
#include "mesh/CellPolygons.h"
#include "post/Normals.h"

#include <fluidsurf/AdaptiveGrid.h>
#include <fluidsurf/Error.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
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
    std::vector<Key> corners; // 3 per triangle
    std::vector<VertexRecord> vertices;
    std::vector<Segment> segments;
    size_t cells[2] = {0, 0}, triangles[2] = {0, 0};
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
    VertexRecord level2Vertex(const Coord& p, int axis, float a, float b) const
    {
        const float m = adaptive::midValue(a, b);
        const bool firstHalf = mesh::inside(a) != mesh::inside(m);
        return {keyOf(firstHalf ? p : offset(p, axis, 1), axis),
                world(p, axis, 2 * mesh::crossing(a, b))};
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
        const size_t before = out.corners.size();
        for (int s = 0; s < n * n * n; ++s) {
            const int si[3] = {s % n, s / n % n, s / (n * n)};
            const Coord sub(origin.x() + step * si[0], origin.y() + step * si[1],
                            origin.z() + step * si[2]);
            float c[8];
            bool complete = true;
            for (int k = 0; k < 8 && complete; ++k) {
                const Coord p(sub.x() + step * mesh::kCorner[k][0],
                              sub.y() + step * mesh::kCorner[k][1],
                              sub.z() + step * mesh::kCorner[k][2]);
                complete = level == kLevel3
                               ? v3.probeValue(p, c[k])
                               : v2.probeValue(Coord(p.x() >> 1, p.y() >> 1, p.z() >> 1), c[k]);
            }
            if (!complete) continue;
            int config = 0;
            for (int k = 0; k < 8; ++k)
                config |= int(mesh::inside(c[k])) << k;
            if (config == 0 || config == 255) continue;
            const mesh::CellPolygons polygons(c);
            VertexRecord vertex[12];
            for (int e = 0; e < 12; ++e) {
                if (polygons.next[e] < 0) continue;
                const int low = mesh::kEdges.lowCorner[e], axis = mesh::kEdges.axis[e];
                const Coord p(sub.x() + step * mesh::kCorner[low][0],
                              sub.y() + step * mesh::kCorner[low][1],
                              sub.z() + step * mesh::kCorner[low][2]);
                const float a = c[low], b = c[low | 1 << axis];
                vertex[e] = level == kLevel2 ? level2Vertex(p, axis, a, b)
                                             : level3Vertex(p, axis, a, b, levels, v2);
                out.vertices.push_back(vertex[e]);
            }
            int number = 0;
            polygons.forEach([&](const int* edges, int count) {
                const uint32_t first = uint32_t(out.corners.size() / 3);
                const bool fan = !polygons.ambiguous || count == 3;
                if (fan) {
                    for (int k = 1; k + 1 < count; ++k)
                        out.corners.insert(
                            out.corners.end(),
                            {vertex[edges[0]].key, vertex[edges[k]].key, vertex[edges[k + 1]].key});
                } else {
                    Vec3d centre(0.0); // summed as the uniform mesher sums it
                    for (int k = 0; k < count; ++k)
                        centre += toVec3d(vertex[edges[k]].point) / count;
                    const VertexRecord mid{keyOf(sub, 3 + number), toVec3f(centre)};
                    out.vertices.push_back(mid);
                    for (int k = 0; k < count; ++k)
                        out.corners.insert(out.corners.end(), {mid.key, vertex[edges[k]].key,
                                                               vertex[edges[(k + 1) % count]].key});
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
                    out.segments.push_back({keyOf(square, axis), vertex[e].key,
                                            vertex[polygons.next[e]].key, blockNumber,
                                            first + uint32_t(t), level == kLevel2});
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
/// becomes a Split (that edge's triangle is cut at the level-3 points: no sliver in the face
/// plane, where the level-3 path can run straight along the level-2 edge); any other loop is
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

TriangleMesh meshAdaptiveGrid(const AdaptiveGrid& grid, Context& ctx, AdaptiveMeshStats* stats)
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
    tbb::parallel_for(size_t(0), blocks.size(), [&](size_t b) {
        ctx.checkpoint();
        adaptive::LevelLookup levels(grid.levels->tree());
        FloatAccessor v2(grid.level2->tree()), v3(grid.level3->tree());
        const size_t end = std::min(cells.size(), (b + 1) * kCellsPerBlock);
        for (size_t i = b * kCellsPerBlock; i < end; ++i)
            mesher.cell(cells[i].first, cells[i].second, levels, v2, v3, uint32_t(b), blocks[b]);
        // Most vertices are found by several cells of the block: one record each before the
        // global sort.
        auto& v = blocks[b].vertices;
        std::sort(v.begin(), v.end(),
                  [](const VertexRecord& x, const VertexRecord& y) { return x.key < y.key; });
        v.erase(std::unique(
                    v.begin(), v.end(),
                    [](const VertexRecord& x, const VertexRecord& y) { return x.key == y.key; }),
                v.end());
    });

    AdaptiveMeshStats s;
    std::vector<VertexRecord> vertices;
    std::vector<Segment> segments;
    size_t cornerCount = 0;
    for (const Block& b : blocks) {
        vertices.insert(vertices.end(), b.vertices.begin(), b.vertices.end());
        segments.insert(segments.end(), b.segments.begin(), b.segments.end());
        cornerCount += b.corners.size();
        s.level2Cells += b.cells[0], s.level3Cells += b.cells[1];
        s.level2Triangles += b.triangles[0], s.level3Triangles += b.triangles[1];
    }
    // One vertex per key (every record of a key carries the same point).
    tbb::parallel_sort(vertices.begin(), vertices.end(),
                       [](const VertexRecord& a, const VertexRecord& b) { return a.key < b.key; });
    vertices.erase(
        std::unique(vertices.begin(), vertices.end(),
                    [](const VertexRecord& a, const VertexRecord& b) { return a.key == b.key; }),
        vertices.end());
    if (vertices.size() >= (size_t(1) << 32))
        throw ValueError("the adaptive grid has more than 2^32 surface vertices");
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
            const std::vector<Key>& k = blocks[b].corners;
            for (size_t t = 0; t < k.size() / 3; ++t)
                mesh.triangles[first[b] + t] = {indexOf(k[3 * t]), indexOf(k[3 * t + 1]),
                                                indexOf(k[3 * t + 2])};
        });
    }
    // Splits: a triangle cut by cracks is fanned from the corner opposite each cut edge through
    // the crack's level-3 points, one cut after the other (a level-2 cell's corner triangle can
    // be cut on two edges, by two level-3 faces).
    const size_t before = mesh.triangles.size();
    {
        std::vector<std::pair<size_t, const Split*>> cut;
        for (size_t q = 0; q < squares; ++q)
            for (const Split& sp : splits[q])
                cut.emplace_back(first[sp.block] + sp.triangle, &sp);
        std::sort(cut.begin(), cut.end(),
                  [](const auto& a, const auto& b) { return a.first < b.first; });
        std::vector<std::array<uint32_t, 3>> pieces;
        for (size_t i = 0; i < cut.size();) {
            const size_t tri = cut[i].first;
            pieces.assign(1, mesh.triangles[tri]);
            for (; i < cut.size() && cut[i].first == tri; ++i) {
                const Split& sp = *cut[i].second;
                const uint32_t a = indexOf(sp.a), b = indexOf(sp.b);
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
                    const uint32_t next = j < sp.between.size() ? indexOf(sp.between[j]) : b;
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
    post::computeAngleWeightedNormals(mesh);
    if (stats) *stats = s;
    return mesh;
}

} // namespace fluidsurf
