// AdaptiveGrid.cc - the adaptive grid's three VDB grids as a set (fluidsurf/AdaptiveGrid.h).
#include <fluidsurf/AdaptiveGrid.h>
#include <fluidsurf/Error.h>

#include <cmath>

namespace fluidsurf {

openvdb::GridPtrVec AdaptiveGrid::grids() const
{
    if (empty()) return {};
    return {level2, level3, levels};
}

AdaptiveGrid AdaptiveGrid::fromGrids(const openvdb::GridPtrVec& grids, const std::string& source)
{
    AdaptiveGrid g;
    openvdb::GridBase::Ptr levels, level2, level3;
    for (const auto& grid : grids) {
        if (grid->getName() == kLevelsName) levels = grid;
        if (grid->getName() == kLevel2Name) level2 = grid;
        if (grid->getName() == kLevel3Name) level3 = grid;
    }
    if (!levels) return g;
    auto fail = [&](const std::string& why) {
        throw InputError(source + ": an adaptive grid (it has a '" + kLevelsName + "' grid) " +
                         why);
    };
    g.levels = openvdb::GridBase::grid<openvdb::Int32Grid>(levels);
    g.level2 = openvdb::GridBase::grid<openvdb::FloatGrid>(level2);
    g.level3 = openvdb::GridBase::grid<openvdb::FloatGrid>(level3);
    if (!g.levels) fail("whose '" + std::string(kLevelsName) + "' grid is not an int32 grid");
    if (!g.level2 || !g.level3)
        fail("without float grids '" + std::string(kLevel2Name) + "' and '" + kLevel3Name + "'");
    const double d4 = g.levels->voxelSize()[0], d2 = g.level2->voxelSize()[0],
                 d1 = g.level3->voxelSize()[0];
    for (const auto& grid : {levels, level2, level3})
        if (!grid->hasUniformVoxels() || !grid->transform().isLinear())
            fail("whose grid '" + grid->getName() + "' has no uniform linear transform");
    if (!(d1 > 0) || !std::isfinite(d1) || std::abs(d2 - 2 * d1) > 1e-9 * d2 ||
        std::abs(d4 - 4 * d1) > 1e-9 * d4)
        fail("whose voxel sizes are not 4:2:1 (" + std::to_string(d4) + ", " + std::to_string(d2) +
             ", " + std::to_string(d1) + ")");
    return g;
}

} // namespace fluidsurf
