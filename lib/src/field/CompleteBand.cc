// CompleteBand.cc - grow the band where a zero crossing reaches its edge.
#include "field/CompleteBand.h"

#include "field/LeafBits.h"

#include <openvdb/tree/LeafManager.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <cmath>
#include <memory>
#include <vector>

namespace fluidsurf {
namespace field {

namespace {
constexpr int kMaxRounds = 32;

/// Inactive voxels the band needs: the axis neighbours of active voxels with |phi| < threshold
/// (the zero crossing may lie just beyond them), and the corners of the 4 cells around every
/// edge with a sign change between active voxels (so that marching cubes, which triangulates
/// complete cells only, closes the surface there).
struct FrontierFinder
{
    const openvdb::FloatTree& tree;
    float threshold;
    bool bothEnds; // look for crossings from both ends of each edge (scanning only new voxels)
    Context& ctx;
    openvdb::MaskTree::Ptr front{new openvdb::MaskTree(false)};

    FrontierFinder(const openvdb::FloatTree& t, float th, bool both, Context& c)
        : tree(t), threshold(th), bothEnds(both), ctx(c)
    {
    }
    FrontierFinder(FrontierFinder& o, tbb::split)
        : tree(o.tree), threshold(o.threshold), bothEnds(o.bothEnds), ctx(o.ctx)
    {
    }

    template <typename Range> void operator()(const Range& range)
    {
        ctx.checkpoint();
        openvdb::tree::ValueAccessor<const openvdb::FloatTree> acc(tree);
        openvdb::tree::ValueAccessor<openvdb::MaskTree> out(*front);
        for (auto leaf = range.begin(); leaf; ++leaf) {
            // The scanned voxels are active in tree: read their own leaf directly, others
            // through the accessor.
            const FloatLeaf* home = tree.probeConstLeaf(leaf->origin());
            Directions dirs = frontierCandidates(*home, threshold, acc);
            // only the scanned voxels' (after the first round, those the last one added: a
            // leaf whose new voxels have nothing to find needs no shell of neighbours)
            uint64_t any = 0;
            for (Words& d : dirs)
                for (int x = 0; x < 8; ++x)
                    any |= d[x] &= leaf->getValueMask().template getWord<uint64_t>(x);
            if (!any) continue;
            const EdgeStencils stencils = edgeStencils(activeShell(*home, acc));
            const std::array<Words, 3>& full = stencils.full;
            // Passed over a word at a time, as the loop below would pass them one by one: an
            // edge whose 18 corners are all active (full: its far end is active, so only a sign
            // change can have put it here, and every corner it would add is there), from
            // either end; and, in the first round, the edges to an active neighbour at -1
            // (their crossings are taken from the other end). Most of the band's crossings
            // are such edges; the neighbour leaves' voxels count (LeafBits.h).
            for (int axis = 0; axis < 3; ++axis)
                for (int x = 0; x < 8; ++x) {
                    dirs[2 * axis + 1][x] &= ~full[axis][x];
                    dirs[2 * axis][x] &=
                        ~(bothEnds ? stencils.fullBelow[axis][x] : stencils.activeBelow[axis][x]);
                }
            Words keep{};
            for (const Words& d : dirs)
                for (int x = 0; x < 8; ++x)
                    keep[x] |= d[x];
            if (keep == Words{}) continue;
            auto probe = [&](const openvdb::Coord& m, float& w) {
                const openvdb::Coord l = m - leaf->origin();
                if ((unsigned(l.x()) | unsigned(l.y()) | unsigned(l.z())) < FloatLeaf::DIM) {
                    const openvdb::Index i = FloatLeaf::coordToOffset(l);
                    w = home->getValue(i);
                    return home->isValueOn(i);
                }
                return acc.probeValue(m, w);
            };
            for (int x = 0; x < 8; ++x)
                for (uint64_t bits = keep[x]; bits; bits &= bits - 1) {
                    const int bit = __builtin_ctzll(bits);
                    const openvdb::Coord c = leaf->origin() + openvdb::Coord(x, bit >> 3, bit & 7);
                    const float value = home->getValue(openvdb::Index(64 * x + bit));
                    const bool in = value < 0;
                    for (int axis = 0; axis < 3; ++axis) {
                        for (int step : {-1, 1}) {
                            if (!(dirs[2 * axis + (step > 0)][x] >> bit & 1)) continue;
                            openvdb::Coord n = c;
                            n[axis] += step;
                            float w;
                            if (!probe(n, w)) {
                                if (std::abs(value) < threshold) out.setValueOn(n);
                            } else if ((w < 0) != in && (bothEnds || step == 1)) {
                                if (step == 1 && (full[axis][x] >> bit & 1)) continue;
                                // Sign change on this edge: the 4 cells around it, 18 corners.
                                const openvdb::Coord low = step == 1 ? c : n;
                                const int b = (axis + 1) % 3, d = (axis + 2) % 3;
                                for (int i = 0; i <= 1; ++i)
                                    for (int j = -1; j <= 1; ++j)
                                        for (int k = -1; k <= 1; ++k) {
                                            openvdb::Coord m = low;
                                            m[axis] += i, m[b] += j, m[d] += k;
                                            float unused;
                                            if (!probe(m, unused)) out.setValueOn(m);
                                        }
                            }
                        }
                    }
                }
        }
    }
    /// (the other's nodes moved in where this has none: see narrowband/NarrowBand.cc's join)
    void join(FrontierFinder& other) { front->merge(*other.front, openvdb::MERGE_ACTIVE_STATES); }
};

/// grown's active voxels, with their values, into tree (where they are inactive). The leaves
/// they need are made first, one after the other (a leaf made in a tile takes the tile's value
/// for its other voxels, as setValue would give them); then each leaf's voxels go in, leaves on
/// all threads. (Voxel by voxel through an accessor, this was one thread's work: 10 ms of the
/// first round on the 1.7M-particle frame, as long as the scan on 16 threads.)
void insertValues(const openvdb::FloatTree& grown, openvdb::FloatTree& tree)
{
    openvdb::tree::LeafManager<const openvdb::FloatTree> from(grown);
    std::vector<FloatLeaf*> to(from.leafCount());
    {
        openvdb::tree::ValueAccessor<openvdb::FloatTree> acc(tree);
        for (size_t i = 0; i < to.size(); ++i)
            to[i] = acc.touchLeaf(from.leaf(i).origin());
    }
    tbb::parallel_for(tbb::blocked_range<size_t>(0, to.size()),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i) {
                              const FloatLeaf& src = from.leaf(i);
                              for (auto v = src.cbeginValueOn(); v; ++v)
                                  to[i]->setValueOn(v.pos(), *v);
                          }
                      });
}
} // namespace

size_t completeBand(openvdb::FloatTree& tree, const Level& level, const FieldEvaluator& evaluate,
                    Context& ctx)
{
    const float threshold = float(0.5 * level.voxelSize);
    size_t added = 0;
    // The first round scans the whole band; later rounds only the voxels the previous one added
    // (edges are checked from both ends, so a new voxel finds its crossings with old ones).
    openvdb::FloatTree::Ptr lastAdded;
    for (int round = 0; round < kMaxRounds; ++round) {
        FrontierFinder finder(tree, threshold, lastAdded != nullptr, ctx);
        {
            openvdb::tree::LeafManager<const openvdb::FloatTree> leaves(lastAdded ? *lastAdded
                                                                                  : tree);
            tbb::parallel_reduce(leaves.leafRange(), finder);
        }
        const size_t count = finder.front->activeVoxelCount();
        if (count == 0) break;
        auto grown = std::make_shared<openvdb::FloatTree>(*finder.front, tree.background(),
                                                          openvdb::TopologyCopy());
        evaluate(*grown);
        insertValues(*grown, tree);
        added += count;
        lastAdded = grown;
    }
    return added;
}

} // namespace field
} // namespace fluidsurf
