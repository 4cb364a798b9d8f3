// AttributeGrids.cc - attributes at a level set's active voxels, as grids of its topology: the
// voxels are listed leaf by leaf (parallel, offsets from a prefix sum), transferred as points,
// and written back into topology copies in the same order.
#include <fluidsurf/TransferAttributes.h>

#include "util/Threads.h"

#include <openvdb/tree/LeafManager.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>

namespace fluidsurf {

namespace {

using FloatTree = openvdb::FloatTree;

/// A grid of tree's topology whose active voxels take value(i) for the i-th active voxel in
/// leaf order.
template <typename GridT, typename ValueFn>
typename GridT::Ptr gridOf(const openvdb::FloatGrid& ls, const std::vector<size_t>& offsets,
                           const std::string& name, ValueFn value)
{
    using TreeT = typename GridT::TreeType;
    auto tree = std::make_shared<TreeT>(
        ls.tree(), typename GridT::ValueType(openvdb::zeroVal<typename GridT::ValueType>()),
        openvdb::TopologyCopy());
    openvdb::tree::LeafManager<TreeT> leaves(*tree);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.leafCount()),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t l = r.begin(); l != r.end(); ++l) {
                              size_t i = offsets[l];
                              for (auto it = leaves.leaf(l).beginValueOn(); it; ++it, ++i)
                                  it.setValue(value(i));
                          }
                      });
    auto grid = GridT::create(tree);
    grid->setTransform(ls.transform().copy());
    grid->setName(name);
    return grid;
}

bool fitsInt32(const std::vector<int64_t>& v)
{
    return std::all_of(v.begin(), v.end(),
                       [](int64_t x) { return x >= INT32_MIN && x <= INT32_MAX; });
}

} // namespace

openvdb::GridPtrVec attributeGrids(const ParticleSet& ps, const std::vector<std::string>& names,
                                   const openvdb::FloatGrid& ls, double R, Context& ctx)
{
    checkAttributeNames(ps, names);
    if (names.empty()) return {};
    // the active voxels' world positions, leaf by leaf (a topology copy walks leaves alike)
    openvdb::tree::LeafManager<const FloatTree> leaves(ls.tree());
    std::vector<size_t> offsets(leaves.leafCount() + 1, 0);
    for (size_t l = 0; l < leaves.leafCount(); ++l)
        offsets[l + 1] = offsets[l] + leaves.leaf(l).onVoxelCount();
    std::vector<Vec3f> points(offsets.back());
    util::withThreads(ctx, [&] {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.leafCount()),
                          [&](const tbb::blocked_range<size_t>& r) {
                              for (size_t l = r.begin(); l != r.end(); ++l) {
                                  size_t i = offsets[l];
                                  for (auto it = leaves.leaf(l).cbeginValueOn(); it; ++it, ++i) {
                                      const openvdb::Vec3d w =
                                          ls.transform().indexToWorld(it.getCoord());
                                      points[i] = Vec3f(float(w.x()), float(w.y()), float(w.z()));
                                  }
                              }
                          });
    });
    const std::vector<Attribute> values = transferAttributes(ps, names, points, R, ctx);
    openvdb::GridPtrVec grids;
    util::withThreads(ctx, [&] {
        for (const Attribute& a : values) {
            const size_t c = size_t(a.components);
            if (a.type == AttributeType::Float && c == 3) {
                grids.push_back(gridOf<openvdb::Vec3fGrid>(ls, offsets, a.name, [&](size_t i) {
                    return openvdb::Vec3f(a.floats[3 * i], a.floats[3 * i + 1],
                                          a.floats[3 * i + 2]);
                }));
                continue;
            }
            for (size_t k = 0; k < c; ++k) {
                const std::string name = c == 1 ? a.name : a.name + std::to_string(k);
                if (a.type == AttributeType::Float)
                    grids.push_back(gridOf<openvdb::FloatGrid>(
                        ls, offsets, name, [&](size_t i) { return a.floats[i * c + k]; }));
                else if (fitsInt32(a.ints))
                    grids.push_back(gridOf<openvdb::Int32Grid>(
                        ls, offsets, name, [&](size_t i) { return int32_t(a.ints[i * c + k]); }));
                else
                    grids.push_back(gridOf<openvdb::Int64Grid>(
                        ls, offsets, name, [&](size_t i) { return a.ints[i * c + k]; }));
            }
        }
    });
    return grids;
}

} // namespace fluidsurf
