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

/// Inactive voxels the band needs: the axis neighbours of active voxels with |phi| < threshold
/// (the zero crossing may lie just beyond them), and the 26 neighbours of every voxel with a sign
/// change to an active axis neighbour (so that all 8 cells around it are complete and marching
/// cubes closes the surface there).
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
                const openvdb::Coord c = v.getCoord();
                const bool in = *v < 0;
                bool crossing = false;
                for (int axis = 0; axis < 3; ++axis)
                    for (int step : {-1, 1}) {
                        openvdb::Coord n = c;
                        n[axis] += step;
                        float w;
                        if (acc.probeValue(n, w)) crossing |= (w < 0) != in;
                        else if (std::abs(*v) < threshold) out.setValueOn(n);
                    }
                if (!crossing) continue;
                for (int dx = -1; dx <= 1; ++dx)
                    for (int dy = -1; dy <= 1; ++dy)
                        for (int dz = -1; dz <= 1; ++dz) {
                            const openvdb::Coord n = c.offsetBy(dx, dy, dz);
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
