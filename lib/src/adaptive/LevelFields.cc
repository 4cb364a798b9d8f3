// LevelFields.cc - rounds of: masks of the new cells' points, evaluation of what no tree holds
// yet, copies and sub-samples, then the completion check.
#include "adaptive/LevelFields.h"
#include "adaptive/LevelMap.h"

#include <openvdb/tree/LeafManager.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <mutex>

namespace fluidsurf {
namespace adaptive {

namespace {

using FloatTree = openvdb::FloatTree;
using MaskTree = openvdb::MaskTree;

/// The union of what f(cell, accessor) marks for each cell, built in parallel.
template <typename F> MaskTree maskOfCells(const std::vector<Coord>& cells, Context& ctx, F f)
{
    struct Body
    {
        const std::vector<Coord>& cells;
        Context& ctx;
        const F& f;
        MaskTree mask;
        Body(const std::vector<Coord>& c, Context& x, const F& g) : cells(c), ctx(x), f(g) {}
        Body(Body& o, tbb::split) : cells(o.cells), ctx(o.ctx), f(o.f) {}
        void join(Body& o) { mask.topologyUnion(o.mask); }
        void operator()(const tbb::blocked_range<size_t>& r)
        {
            ctx.checkpoint();
            openvdb::tree::ValueAccessor<MaskTree> acc(mask);
            for (size_t i = r.begin(); i != r.end(); ++i)
                f(cells[i], acc);
        }
    } body(cells, ctx, f);
    tbb::parallel_reduce(tbb::blocked_range<size_t>(0, cells.size(), 64), body);
    return std::move(body.mask);
}

inline Coord scaled(const Coord& c, int n)
{
    return Coord(c.x() * n, c.y() * n, c.z() * n);
}

/// Calls f(voxel iterator, state) for every active voxel of tree, in parallel over its leaves,
/// with a State made per leaf (its accessors); f may change the value or switch the voxel off.
template <typename MakeState, typename F>
void forEachVoxel(FloatTree& tree, Context& ctx, MakeState makeState, F f)
{
    openvdb::tree::LeafManager<FloatTree> leaves(tree);
    leaves.foreach ([&](FloatTree::LeafNodeType& leaf, size_t) {
        ctx.checkpoint();
        auto state = makeState();
        for (auto v = leaf.beginValueOn(); v; ++v)
            f(v, state);
    });
}

/// The value a level-3 point takes from level 2: copied at a level-2 point (clamped to the
/// level-3 background, as the field evaluated at level 3 would be), else sub-sampled (one odd
/// coordinate: the middle of a level-2 edge; two: the centre of a level-2 face).
float fromLevel2(const Coord& p, openvdb::tree::ValueAccessor<const FloatTree>& level2,
                 float background3)
{
    int odd[3], n = 0;
    for (int a = 0; a < 3; ++a)
        if (p[a] & 1) odd[n++] = a;
    auto at = [&](Coord q) { return level2.getValue(Coord(q.x() >> 1, q.y() >> 1, q.z() >> 1)); };
    if (n == 0) return std::clamp(at(p), -background3, background3);
    Coord lo = p, hi = p;
    lo[odd[0]] -= 1, hi[odd[0]] += 1;
    if (n == 1) return midValue(at(lo), at(hi));
    Coord a = lo, b = lo, c = hi, d = hi; // a, c and b, d opposite corners
    a[odd[1]] -= 1, b[odd[1]] += 1, c[odd[1]] += 1, d[odd[1]] -= 1;
    return centreValue(at(a), at(b), at(c), at(d));
}

/// Cells not yet meshed that share a sign-changing boundary edge with cell (at its level:
/// step 1 in the level-3 tree, step 2 in level-2 coordinates times two). Only the unmeshed
/// neighbours' shared faces and edges are read: most cells have none.
void unmeshedNeighbours(const Coord& cell, int level, LevelLookup& levels,
                        openvdb::tree::ValueAccessor<const FloatTree>& values,
                        std::vector<Coord>& out)
{
    const int n = level == kLevel3 ? 4 : 2; // cells per coarse cell along an axis
    const Coord origin = scaled(cell, n);
    auto crosses = [&](Coord p, int axis) { // the lattice edge from origin + p along axis
        p += origin;
        Coord q = p;
        q[axis] += 1;
        return (values.getValue(p) < 0) != (values.getValue(q) < 0);
    };
    for (int i = 0; i < 27; ++i) {
        const Coord d(i % 3 - 1, i / 3 % 3 - 1, i / 9 - 1);
        int offAxes = 0, axes[3];
        for (int a = 0; a < 3; ++a)
            if (d[a]) axes[offAxes++] = a;
        if (offAxes == 0 || offAxes == 3 || levels.level(cell + d) != 0) continue;
        bool found = false;
        if (offAxes == 1) { // a face: the edges in its plane, along either other axis
            const int f = axes[0];
            for (int e = 1; e <= 2 && !found; ++e) {
                const int a = (f + e) % 3, b = (f + 3 - e) % 3;
                for (int t = 0; t < n && !found; ++t)
                    for (int u = 0; u <= n && !found; ++u) {
                        Coord p(0);
                        p[f] = d[f] > 0 ? n : 0, p[a] = t, p[b] = u;
                        found = crosses(p, a);
                    }
            }
        } else { // an edge: the lattice edges along it
            int a = 0;
            while (d[a])
                ++a;
            for (int t = 0; t < n && !found; ++t) {
                Coord p(0);
                p[axes[0]] = d[axes[0]] > 0 ? n : 0, p[axes[1]] = d[axes[1]] > 0 ? n : 0;
                p[a] = t;
                found = crosses(p, a);
            }
        }
        if (found) out.push_back(cell + d);
    }
}

/// How far the surface moves (world units) when a probe's level-3 value v replaces what level 2
/// interpolates there. On a level-2 edge from value a to b: the crossing itself moves, from the
/// level-2 edge's to the level-3 half-edge's. At a cell centre: the value's change over the
/// gradient's length (at least 1/4: phi is about a distance), the gradient from the cell's
/// corners.
struct Probe
{
    float a = 0, b = 0;     // edge: the end values
    float interpolated = 0; // centre: the corners' mean
    double gradient = 0;    // centre: |grad phi|
    double dx = 0;          // the level-3 voxel
    bool edge = false;
    double displacement(float v) const
    {
        if (!edge) return std::abs(double(v) - interpolated) / std::max(gradient, 0.25);
        const double coarse = 2 * double(a) / (double(a) - double(b));
        const double fine = (a < 0) != (v < 0) ? double(a) / (double(a) - double(v))
                                               : 1 + double(v) / (double(v) - double(b));
        return std::abs(coarse - fine) * dx;
    }
};

/// Level-3 probes of a level-2 cell where its surface is: the centre of each of its level-2
/// cells with a sign change, and the middle of each level-2 edge and the centre of each face
/// with one. f(point, Probe).
/// (Probing near the surface as well, where a corner is within two voxels of it, refined nearly
/// every cell of the generated drop for little gain.)
template <typename F>
void forEachProbe(const Coord& cell, openvdb::tree::ValueAccessor<const FloatTree>& level2,
                  double dx, F&& f)
{
    for (int s = 0; s < 8; ++s) {
        const Coord sub(2 * cell.x() + (s & 1), 2 * cell.y() + (s >> 1 & 1),
                        2 * cell.z() + (s >> 2)); // level-2 index
        float c[8];
        int inside = 0;
        for (int k = 0; k < 8; ++k) {
            if (!level2.probeValue(
                    Coord(sub.x() + (k & 1), sub.y() + (k >> 1 & 1), sub.z() + (k >> 2)), c[k]))
                return;
            inside += c[k] < 0;
        }
        if (inside == 0 || inside == 8) continue;
        double mean = 0, g[3] = {0, 0, 0};
        for (int k = 0; k < 8; ++k) {
            mean += c[k] / 8.0;
            for (int a = 0; a < 3; ++a)
                g[a] += (k >> a & 1 ? c[k] : -c[k]) / 8.0; // per level-3 voxel: / 2, times 4 / 8
        }
        Probe centre;
        centre.interpolated = float(mean), centre.dx = dx;
        centre.gradient = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]) / dx;
        const Coord p(2 * sub.x(), 2 * sub.y(), 2 * sub.z());
        f(p + Coord(1, 1, 1), centre);
        // Face centres of faces with a sign change: a bump between the level-2 lines that
        // neither the edges nor the cell centres see (the flat bottom of a dam break).
        for (int axis = 0; axis < 3; ++axis)
            for (int side = 0; side < 2; ++side) {
                float v[4];
                int n = 0, in = 0;
                for (int k = 0; k < 8; ++k)
                    if ((k >> axis & 1) == side) v[n] = c[k], in += c[k] < 0, ++n;
                if (in == 0 || in == 4) continue;
                Probe face = centre;
                face.interpolated = 0.25f * ((v[0] + v[3]) + (v[1] + v[2]));
                Coord q = p + Coord(1, 1, 1);
                q[axis] += side ? 1 : -1;
                f(q, face);
            }
        for (int k = 0; k < 8; ++k)
            for (int a = 0; a < 3; ++a)
                if (!(k >> a & 1) && (c[k] < 0) != (c[k | 1 << a] < 0)) {
                    Coord m(p.x() + 2 * (k & 1), p.y() + 2 * (k >> 1 & 1), p.z() + 2 * (k >> 2));
                    m[a] += 1;
                    Probe edge;
                    edge.a = c[k], edge.b = c[k | 1 << a], edge.edge = true, edge.dx = dx;
                    f(m, edge);
                }
    }
}

/// Level-2 cells where level 2 misses the field by more than tolerance at a probe become level
/// 3. Returns the evaluated probes (level-3 values, reused by the level-3 cells).
FloatTree::Ptr refineWhereLevel2Misses(const FloatTree& level2, LevelTree& levels,
                                       const field::FieldEvaluator& evaluate3, float background3,
                                       float tolerance, Context& ctx, LevelFieldStats& s)
{
    const double dx = background3 / 3.0; // the level-3 background is three voxels
    std::vector<Coord> flat;
    for (auto v = levels.cbeginValueOn(); v; ++v)
        if (*v == kLevel2) flat.push_back(v.getCoord());
    const MaskTree mask = maskOfCells(flat, ctx, [&](const Coord& c, auto& acc) {
        openvdb::tree::ValueAccessor<const FloatTree> v2(level2);
        forEachProbe(c, v2, dx, [&](const Coord& p, const Probe&) { acc.setValueOn(p); });
    });
    auto probes = std::make_shared<FloatTree>(mask, background3, openvdb::TopologyCopy());
    evaluate3(*probes);
    s.probes = probes->activeVoxelCount();
    std::vector<char> refine(flat.size(), 0);
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, flat.size(), 64), [&](const tbb::blocked_range<size_t>& r) {
            ctx.checkpoint();
            openvdb::tree::ValueAccessor<const FloatTree> v2(level2), pr(*probes);
            for (size_t i = r.begin(); i != r.end(); ++i)
                forEachProbe(flat[i], v2, dx, [&](const Coord& p, const Probe& probe) {
                    if (probe.displacement(pr.getValue(p)) > tolerance) refine[i] = 1;
                });
        });
    for (size_t i = 0; i < flat.size(); ++i)
        if (refine[i]) levels.setValueOn(flat[i], kLevel3), ++s.refinedCells;
    return probes;
}

/// The probes at the middle of a level-2 edge (one odd coordinate), in leaf order: a list, not
/// a tree, for the scattered points would each keep a leaf of the probes' alive.
std::vector<std::pair<Coord, float>> edgeMiddles(const FloatTree& probes)
{
    std::vector<std::pair<Coord, float>> middles;
    for (auto v = probes.cbeginValueOn(); v; ++v) {
        const Coord p = v.getCoord();
        if ((p.x() & 1) + (p.y() & 1) + (p.z() & 1) == 1) middles.emplace_back(p, *v);
    }
    return middles;
}

} // namespace

openvdb::FloatTree::Ptr fillLevels(openvdb::FloatTree& level2, LevelTree& levels,
                                   const field::FieldEvaluator& evaluate2,
                                   const field::FieldEvaluator& evaluate3, float background3,
                                   const Refinement& refinement, Context& ctx,
                                   LevelFieldStats* stats)
{
    const float tolerance = refinement.tolerance;
    LevelFieldStats s;
    auto probes = std::make_shared<FloatTree>(background3);
    std::vector<std::pair<Coord, float>> crossings; // probes at level-2 edges' middles
    bool firstRound = true;
    auto level3 = std::make_shared<FloatTree>(background3);
    std::vector<Coord> cells;
    for (auto v = levels.cbeginValueOn(); v; ++v)
        cells.push_back(v.getCoord());
    const float background2 = level2.background();
    while (!cells.empty()) {
        // Level 2: the 27 level-2 points of every new cell.
        MaskTree want2 = maskOfCells(cells, ctx, [](const Coord& c, auto& acc) {
            for (int i = 0; i < 27; ++i)
                acc.setValueOn(scaled(c, 2) + Coord(i % 3, i / 3 % 3, i / 9));
        });
        want2.topologyDifference(level2);
        if (!want2.empty()) {
            FloatTree grown(want2, background2, openvdb::TopologyCopy());
            evaluate2(grown);
            s.level2Evaluated += grown.activeVoxelCount();
            level2.merge(grown);
        }
        if (firstRound && tolerance > 0) {
            probes =
                refineWhereLevel2Misses(level2, levels, evaluate3, background3, tolerance, ctx, s);
            crossings = edgeMiddles(*probes);
        }
        if (firstRound && refinement.closeIslands) s.islandCells = closeLevel2Islands(levels, ctx);
        firstRound = false;
        // Level 3: the 125 points of every new level-3 cell, split into evaluated and taken from
        // level 2.
        std::vector<Coord> fine;
        {
            openvdb::tree::ValueAccessor<const LevelTree> acc(levels);
            for (const Coord& c : cells)
                if (acc.getValue(c) == kLevel3) fine.push_back(c);
        }
        MaskTree want3 = maskOfCells(fine, ctx, [](const Coord& c, auto& acc) {
            for (int i = 0; i < 125; ++i)
                acc.setValueOn(scaled(c, 4) + Coord(i % 5, i / 5 % 5, i / 25));
        });
        want3.topologyDifference(*level3);
        FloatTree evaluated(want3, background3, openvdb::TopologyCopy());
        forEachVoxel(
            evaluated, ctx, [&] { return LevelLookup(levels); },
            [](auto& v, LevelLookup& lookup) {
                const Coord p = v.getCoord();
                if (!((p.x() | p.y() | p.z()) & 1) || lookup.subsampled(p)) v.setValueOff();
            });
        MaskTree taken(want3);
        taken.topologyDifference(evaluated);
        FloatTree reused(*probes); // probes of cells now at level 3: evaluated already
        reused.topologyIntersection(evaluated);
        evaluated.topologyDifference(*probes);
        evaluate3(evaluated);
        s.level3Evaluated += evaluated.activeVoxelCount();
        evaluated.merge(reused);
        probes = std::make_shared<FloatTree>(background3); // refinement is done: none are left
        level3->merge(evaluated);
        // The copies and sub-samples, written into level 3's own leaves (no tree of their own).
        level3->topologyUnion(taken);
        std::atomic<size_t> copies{0};
        {
            const FloatTree& from = level2;
            openvdb::tree::LeafManager<FloatTree> leaves(*level3);
            leaves.foreach ([&](FloatTree::LeafNodeType& leaf, size_t) {
                ctx.checkpoint();
                const MaskTree::LeafNodeType* mask = taken.probeConstLeaf(leaf.origin());
                if (!mask) return;
                openvdb::tree::ValueAccessor<const FloatTree> acc(from);
                size_t n = 0;
                for (auto v = mask->cbeginValueOn(); v; ++v) {
                    const Coord p = v.getCoord();
                    leaf.setValueOnly(v.pos(), fromLevel2(p, acc, background3));
                    n += !((p.x() | p.y() | p.z()) & 1);
                }
                copies += n;
            });
        }
        s.subsampled += taken.activeVoxelCount() - copies;

        // Completion: unmeshed cells across sign-changing boundary edges, added at level 3.
        std::vector<std::vector<Coord>> found(cells.size());
        tbb::parallel_for(tbb::blocked_range<size_t>(0, cells.size(), 64),
                          [&](const tbb::blocked_range<size_t>& r) {
                              ctx.checkpoint();
                              LevelLookup lookup(levels);
                              openvdb::tree::ValueAccessor<const FloatTree> v2(level2), v3(*level3);
                              for (size_t i = r.begin(); i != r.end(); ++i) {
                                  const int level = lookup.level(cells[i]);
                                  unmeshedNeighbours(cells[i], level, lookup,
                                                     level == kLevel3 ? v3 : v2, found[i]);
                              }
                          });
        std::vector<Coord> added;
        for (auto& f : found)
            added.insert(added.end(), f.begin(), f.end());
        std::sort(added.begin(), added.end());
        added.erase(std::unique(added.begin(), added.end()), added.end());
        for (const Coord& c : added)
            levels.setValueOn(c, kLevel3);
        s.completionCells += added.size();
        cells = std::move(added);
    }
    // The crossings' probes that no level-3 cell reads: they place level 2's vertices.
    std::vector<char> keep(crossings.size(), 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, crossings.size(), 1024),
                      [&](const tbb::blocked_range<size_t>& r) {
                          ctx.checkpoint();
                          LevelLookup lookup(levels);
                          for (size_t i = r.begin(); i != r.end(); ++i)
                              keep[i] = !lookup.touches(crossings[i].first, kLevel3);
                      });
    {
        openvdb::tree::ValueAccessor<FloatTree> acc(*level3);
        for (size_t i = 0; i < crossings.size(); ++i)
            if (keep[i])
                acc.setValueOn(crossings[i].first, crossings[i].second), ++s.crossingProbes;
    }
    if (stats) *stats = s;
    return level3;
}

} // namespace adaptive
} // namespace fluidsurf
