// CompleteBand.cc - grow the band where a zero crossing reaches its edge.
#include "narrowband/CompleteBand.h"

#include "field/GatherField.h"

#include <openvdb/tree/LeafManager.h>

#include <tbb/parallel_reduce.h>

#include <cmath>

namespace fluidsurf {
namespace narrowband {

namespace {
constexpr int kMaxRounds = 32;

/// Inactive axis neighbours of active voxels with |phi| < threshold.
struct FrontierFinder
{
    const openvdb::FloatTree& tree;
    float threshold;
    openvdb::MaskTree::Ptr front{new openvdb::MaskTree(false)};

    FrontierFinder(const openvdb::FloatTree& t, float th) : tree(t), threshold(th) {}
    FrontierFinder(FrontierFinder& o, tbb::split) : tree(o.tree), threshold(o.threshold) {}

    template <typename Range>
    void operator()(const Range& range)
    {
        openvdb::tree::ValueAccessor<const openvdb::FloatTree> acc(tree);
        openvdb::tree::ValueAccessor<openvdb::MaskTree> out(*front);
        for (auto leaf = range.begin(); leaf; ++leaf)
            for (auto v = leaf->cbeginValueOn(); v; ++v) {
                if (!(std::abs(*v) < threshold)) continue;
                const openvdb::Coord c = v.getCoord();
                for (int axis = 0; axis < 3; ++axis)
                    for (int step : {-1, 1}) {
                        openvdb::Coord n = c;
                        n[axis] += step;
                        if (!acc.isValueOn(n)) out.setValueOn(n);
                    }
            }
    }
    void join(FrontierFinder& other) { front->topologyUnion(*other.front); }
};
} // namespace

size_t completeBand(openvdb::FloatTree& tree, const neighbors::CellIndex& particles, const Params& params)
{
    const float threshold = float(0.5 * params.voxelSize);
    size_t added = 0;
    for (int round = 0; round < kMaxRounds; ++round) {
        FrontierFinder finder(tree, threshold);
        {
            openvdb::tree::LeafManager<const openvdb::FloatTree> leaves(tree);
            tbb::parallel_reduce(leaves.leafRange(), finder);
        }
        const size_t count = finder.front->activeVoxelCount();
        if (count == 0) break;
        openvdb::FloatTree grown(*finder.front, tree.background(), openvdb::TopologyCopy());
        field::evaluateField(grown, particles, params);
        openvdb::tree::ValueAccessor<openvdb::FloatTree> acc(tree);
        for (auto v = grown.cbeginValueOn(); v; ++v) acc.setValue(v.getCoord(), *v);
        added += count;
    }
    return added;
}

} // namespace narrowband
} // namespace fluidsurf
