// LevelMap.cc - meshed coarse cells from the level-2 band and the splash particles, then their
// levels from the particles' curvature.
#include "adaptive/LevelMap.h"

#include <openvdb/tree/LeafManager.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>

namespace fluidsurf {
namespace adaptive {

namespace {

using MaskTree = openvdb::MaskTree;

/// Coarse cells around every sign-changing edge of the level-2 band.
struct CrossedCells
{
    const openvdb::FloatTree& band;
    Context& ctx;
    MaskTree cells;

    CrossedCells(const openvdb::FloatTree& b, Context& c) : band(b), ctx(c) {}
    CrossedCells(CrossedCells& other, tbb::split) : band(other.band), ctx(other.ctx) {}
    void join(CrossedCells& other) { cells.topologyUnion(other.cells); }

    void operator()(const openvdb::tree::LeafManager<const openvdb::FloatTree>::LeafRange& range)
    {
        ctx.checkpoint();
        openvdb::tree::ValueAccessor<const openvdb::FloatTree> acc(band);
        openvdb::tree::ValueAccessor<MaskTree> out(cells);
        for (auto leaf = range.begin(); leaf; ++leaf)
            for (auto v = leaf->cbeginValueOn(); v; ++v) {
                const Coord p = v.getCoord(); // level-2 index
                const bool in = *v < 0;
                for (int a = 0; a < 3; ++a) {
                    Coord q = p;
                    q[a] += 1;
                    float w;
                    if (!acc.probeValue(q, w) || (w < 0) == in) continue;
                    // Cells holding the edge: one along a, two across each other axis where the
                    // edge lies on a coarse face (an even level-2 coordinate).
                    int lo[3], hi[3];
                    for (int b = 0; b < 3; ++b) {
                        hi[b] = p[b] >> 1;
                        lo[b] = (b != a && !(p[b] & 1)) ? hi[b] - 1 : hi[b];
                    }
                    for (int z = lo[2]; z <= hi[2]; ++z)
                        for (int y = lo[1]; y <= hi[1]; ++y)
                            for (int x = lo[0]; x <= hi[0]; ++x)
                                out.setValueOn(Coord(x, y, z));
                }
            }
    }
};

/// The coarse cell holding world point p.
Coord cellOf(const Vec3f& p, double coarse)
{
    return Coord(int(std::floor(p.x / coarse)), int(std::floor(p.y / coarse)),
                 int(std::floor(p.z / coarse)));
}

} // namespace

LevelTree::Ptr buildLevelMap(const LevelMapInput& in, Context& ctx)
{
    const double coarse = 4 * in.dx;
    CrossedCells crossed(in.level2, ctx);
    {
        openvdb::tree::LeafManager<const openvdb::FloatTree> leaves(in.level2);
        tbb::parallel_reduce(leaves.leafRange(), crossed);
    }
    // Splash and thin particles: few, serial. Their cells only: where their surface leaves the
    // cell, the completion of the level fields adds the next cell at level 3.
    MaskTree splash;
    for (size_t i = 0; i < in.particles.size(); ++i)
        if (in.classes.classes[i] == classify::Splash ||
            (classify::isSurface(in.classes.classes[i]) && in.classes.neighbours[i] < in.thin))
            splash.setValueOn(cellOf(in.particles.positions[i], coarse));
    auto levels = std::make_shared<LevelTree>(crossed.cells, 0, openvdb::TopologyCopy());
    levels->topologyUnion(splash);
    levels->voxelizeActiveTiles();

    openvdb::tree::LeafManager<LevelTree> leaves(*levels);
    leaves.foreach ([&](LevelTree::LeafNodeType& leaf, size_t) {
        ctx.checkpoint();
        openvdb::tree::ValueAccessor<const MaskTree> isSplash(splash);
        for (auto v = leaf.beginValueOn(); v; ++v) {
            const Coord c = v.getCoord();
            if (isSplash.isValueOn(c)) {
                v.setValue(kLevel3);
                continue;
            }
            // Mean kappa of the surface particles within the band width of the cell.
            const double lo[3] = {c.x() * coarse - in.width, c.y() * coarse - in.width,
                                  c.z() * coarse - in.width};
            const double hi[3] = {lo[0] + coarse + 2 * in.width, lo[1] + coarse + 2 * in.width,
                                  lo[2] + coarse + 2 * in.width};
            double sum = 0;
            size_t n = 0;
            in.particles.forEachCellInBox(lo, hi, [&](uint32_t begin, uint32_t end) {
                for (uint32_t j = begin; j < end; ++j) {
                    if (in.classes.classes[j] != classify::Surface) continue;
                    const Vec3f& p = in.particles.positions[j];
                    if (p.x < lo[0] || p.x > hi[0] || p.y < lo[1] || p.y > hi[1] || p.z < lo[2] ||
                        p.z > hi[2])
                        continue;
                    sum += in.kappa[j], ++n;
                }
            });
            v.setValue(n == 0 || sum >= in.threshold * double(n) ? kLevel3 : kLevel2);
        }
    });
    return levels;
}

size_t closeLevel2Islands(LevelTree& levels, Context& ctx)
{
    std::vector<Coord> candidates;
    for (auto v = levels.cbeginValueOn(); v; ++v)
        if (*v == kLevel2) candidates.push_back(v.getCoord());
    size_t moved = 0;
    while (!candidates.empty()) {
        std::vector<char> island(candidates.size(), 0);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, candidates.size(), 256),
                          [&](const tbb::blocked_range<size_t>& r) {
                              ctx.checkpoint();
                              LevelLookup lookup(levels);
                              for (size_t i = r.begin(); i != r.end(); ++i) {
                                  int at[4] = {0, 0, 0, 0}; // by level: 0, 2 and 3 used
                                  for (int f = 0; f < 6; ++f) {
                                      Coord q = candidates[i];
                                      q[f / 2] += f & 1 ? 1 : -1;
                                      ++at[lookup.level(q)];
                                  }
                                  island[i] = at[kLevel3] > at[kLevel2];
                              }
                          });
        // The next round looks only at the level-2 face neighbours of the cells moved now.
        std::vector<Coord> next;
        for (size_t i = 0; i < candidates.size(); ++i)
            if (island[i]) levels.setValueOn(candidates[i], kLevel3), ++moved;
        LevelLookup lookup(levels);
        for (size_t i = 0; i < candidates.size(); ++i)
            if (island[i])
                for (int f = 0; f < 6; ++f) {
                    Coord q = candidates[i];
                    q[f / 2] += f & 1 ? 1 : -1;
                    if (lookup.level(q) == kLevel2) next.push_back(q);
                }
        std::sort(next.begin(), next.end());
        next.erase(std::unique(next.begin(), next.end()), next.end());
        candidates = std::move(next);
    }
    return moved;
}

} // namespace adaptive
} // namespace fluidsurf
