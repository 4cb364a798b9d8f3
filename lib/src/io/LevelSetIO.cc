// LevelSetIO.cc - level sets in .vdb files: read (validated like every reader), written
// atomically with a content-derived UUID (VdbWrite.h), and described for `fluidsurf info`.
#include <fluidsurf/Error.h>
#include <fluidsurf/io/LevelSetIO.h>

#include "io/FileBuffer.h"
#include "io/VdbGrids.h"
#include "io/VdbWrite.h"

#include <openvdb/tree/LeafManager.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

namespace fluidsurf {
namespace io {

openvdb::FloatGrid::Ptr readLevelSet(const std::string& path, const std::string& gridName)
{
    const std::vector<uint8_t> bytes = io_internal::readFile(path);
    return readLevelSetFromMemory(bytes.data(), bytes.size(), path, gridName);
}

namespace {

/// InputError naming the first voxel or tile whose value is NaN or Inf: meshed, it became NaN
/// or Inf vertices in the output. Tiles are visited once each, not voxel by voxel.
void requireFiniteValues(const openvdb::FloatGrid& grid, const std::string& path)
{
    const openvdb::FloatTree& tree = grid.tree();
    auto fail = [&](const openvdb::Coord& at, float v, const char* what) {
        throw InputError(path + ": grid '" + grid.getName() + "' has the value " +
                         std::to_string(v) + " at the " + what + " (" + std::to_string(at.x()) +
                         ", " + std::to_string(at.y()) + ", " + std::to_string(at.z()) +
                         "); a level set's values must be finite");
    };
    openvdb::FloatTree::ValueAllCIter tile = tree.cbeginValueAll();
    tile.setMaxDepth(openvdb::FloatTree::ValueAllCIter::LEAF_DEPTH - 1);
    for (; tile; ++tile)
        if (!std::isfinite(*tile)) fail(tile.getCoord(), *tile, "tile");
    const openvdb::tree::LeafManager<const openvdb::FloatTree> leaves(tree);
    const size_t bad = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, leaves.leafCount()), leaves.leafCount(),
        [&](const tbb::blocked_range<size_t>& r, size_t first) {
            for (size_t i = r.begin(); i < r.end() && i < first; ++i) {
                const float* v = leaves.leaf(i).buffer().data();
                for (openvdb::Index k = 0; k < openvdb::FloatTree::LeafNodeType::SIZE; ++k)
                    if (!std::isfinite(v[k])) return i;
            }
            return first;
        },
        [](size_t a, size_t b) { return std::min(a, b); });
    if (bad == leaves.leafCount()) return;
    for (auto v = leaves.leaf(bad).cbeginValueAll(); v; ++v)
        if (!std::isfinite(*v)) fail(v.getCoord(), *v, "voxel");
}

/// The grid to mesh among grids (see readLevelSet).
openvdb::FloatGrid::Ptr pickLevelSet(const openvdb::GridPtrVec& grids, const std::string& path,
                                     const std::string& gridName)
{
    openvdb::FloatGrid::Ptr levelSet, anyFloat;
    std::string names;
    for (const openvdb::GridBase::Ptr& g : grids) {
        names += (names.empty() ? "" : ", ") + g->getName() + " (" + g->valueType() + ", " +
                 openvdb::GridBase::gridClassToString(g->getGridClass()) + ")";
        auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
        if (!f) continue;
        if (!gridName.empty()) {
            if (f->getName() == gridName && !levelSet) levelSet = f;
            continue;
        }
        if (!levelSet && f->getGridClass() == openvdb::GRID_LEVEL_SET) levelSet = f;
        if (!anyFloat) anyFloat = f;
    }
    if (!levelSet) levelSet = gridName.empty() ? anyFloat : nullptr;
    if (!levelSet)
        throw InputError(
            path + ": no " +
            (gridName.empty() ? std::string("float grid") : "float grid named '" + gridName + "'") +
            " in this VDB (grids: " + (names.empty() ? std::string("none") : names) + ")");
    const openvdb::Vec3d voxel = levelSet->voxelSize();
    for (int a = 0; a < 3; ++a)
        if (!(std::isfinite(voxel[a]) && voxel[a] > 0))
            throw InputError(path + ": grid '" + levelSet->getName() + "' has voxel size " +
                             std::to_string(voxel[a]) + " (positive and finite expected)");
    if (!std::isfinite(levelSet->background()))
        throw InputError(path + ": grid '" + levelSet->getName() +
                         "' has a background that is not finite");
    requireFiniteValues(*levelSet, path);
    return levelSet;
}

} // namespace

openvdb::FloatGrid::Ptr readLevelSetFromMemory(const uint8_t* data, size_t size,
                                               const std::string& path, const std::string& gridName)
{
    return pickLevelSet(*io_internal::readVdbGrids(data, size, path), path, gridName);
}

LevelSetFile readLevelSetFile(const std::string& path, const std::string& gridName)
{
    const openvdb::GridPtrVecPtr grids =
        io_internal::readVdbGrids(io_internal::readFile(path), path);
    LevelSetFile f;
    if (gridName.empty()) f.adaptive = AdaptiveGrid::fromGrids(*grids, path);
    f.grid = f.adaptive.empty() ? pickLevelSet(*grids, path, gridName) : f.adaptive.level2;
    if (!f.adaptive.empty())
        for (const openvdb::GridBase::Ptr& g : *grids)
            if (auto levels = openvdb::gridPtrCast<openvdb::FloatGrid>(g))
                requireFiniteValues(*levels, path);
    return f;
}

void writeLevelSet(const openvdb::GridPtrVec& grids, const std::string& path)
{
    io_internal::writeVdbFile(openvdb::GridCPtrVec(grids.begin(), grids.end()), path,
                              openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK,
                              /*uuidFromContent=*/true);
}

std::vector<GridDescription> describeVdb(const std::string& path, std::vector<std::string>* skipped)
{
    const openvdb::GridPtrVecPtr grids =
        io_internal::readVdbGrids(io_internal::readFile(path), path, skipped);
    std::vector<GridDescription> out;
    for (const openvdb::GridBase::Ptr& g : *grids) {
        GridDescription d;
        d.name = g->getName();
        d.gridClass = openvdb::GridBase::gridClassToString(g->getGridClass());
        d.valueType = g->valueType();
        const openvdb::Vec3d vs = g->voxelSize();
        for (int a = 0; a < 3; ++a)
            d.voxelSize[a] = vs[a];
        d.linear = g->transform().isLinear();
        d.activeVoxels = g->activeVoxelCount();
        d.leaves = g->baseTreePtr()->leafCount();
        const openvdb::CoordBBox box = g->evalActiveVoxelBoundingBox();
        d.empty = box.empty();
        if (!d.empty)
            for (int a = 0; a < 3; ++a)
                d.bboxMin[a] = box.min()[a], d.bboxMax[a] = box.max()[a];
        if (auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g)) {
            char text[32];
            std::snprintf(text, sizeof(text), "%g", double(f->background()));
            d.background = text;
        }
        for (auto m = g->beginMeta(); m != g->endMeta(); ++m)
            if (m->second) d.metadata.emplace_back(m->first, m->second->str());
        out.push_back(std::move(d));
    }
    return out;
}

} // namespace io
} // namespace fluidsurf
