// LevelSet.cc - finishing and writing level sets.
#include "levelset/LevelSet.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Version.h>

#include <openvdb/tools/Prune.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tree/LeafManager.h>

#include <vector>

namespace fluidsurf {
namespace levelset {

namespace {
void deactivateOutsideBand(openvdb::FloatTree& tree, float background, Context& ctx)
{
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(tree);
    leaves.foreach ([background, &ctx](openvdb::FloatTree::LeafNodeType& leaf, size_t i) {
        if (i % 64 == 0) ctx.checkpoint();
        for (auto v = leaf.beginValueOn(); v; ++v)
            if (std::abs(*v) >= background) v.setValueOff();
    });
}
} // namespace

openvdb::FloatGrid::Ptr finishLevelSet(openvdb::FloatTree::Ptr tree, const Params& params,
                                       const Level& level, bool keepOnlyBand, const GridInfo& info,
                                       Context& ctx)
{
    const float background = float(params.background(level));
    if (keepOnlyBand) deactivateOutsideBand(*tree, background, ctx);
    openvdb::tools::signedFloodFill(*tree);
    openvdb::tools::pruneLevelSet(*tree);
    auto grid = openvdb::FloatGrid::create(tree);
    grid->setTransform(level.transform());
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    grid->setName("surface");
    grid->insertMeta("fluidsurf:particle_radius", openvdb::DoubleMetadata(params.radius));
    grid->insertMeta("fluidsurf:influence_radius", openvdb::DoubleMetadata(params.influenceRadius));
    grid->insertMeta("fluidsurf:smoothing_length", openvdb::DoubleMetadata(params.smoothingLength));
    grid->insertMeta("fluidsurf:t_low", openvdb::DoubleMetadata(params.tLow));
    grid->insertMeta("fluidsurf:t_high", openvdb::DoubleMetadata(params.tHigh));
    grid->insertMeta("fluidsurf:field", openvdb::StringMetadata(fieldName(params.field)));
    grid->insertMeta("fluidsurf:method", openvdb::StringMetadata(methodName(params.method)));
    grid->insertMeta("fluidsurf:particle_count", openvdb::Int64Metadata(int64_t(info.particles)));
    grid->insertMeta("fluidsurf:isolated_particles",
                     openvdb::Int64Metadata(int64_t(info.isolated)));
    grid->insertMeta("fluidsurf:source", openvdb::StringMetadata(info.source));
    grid->insertMeta("fluidsurf:version", openvdb::StringMetadata(FLUIDSURF_VERSION_STRING));
    return grid;
}

} // namespace levelset

std::vector<std::string> levelSetMetadataNames()
{
    return {
        "fluidsurf:particle_radius", "fluidsurf:influence_radius", "fluidsurf:smoothing_length",
        "fluidsurf:t_low",           "fluidsurf:t_high",           "fluidsurf:field",
        "fluidsurf:method",          "fluidsurf:particle_count",   "fluidsurf:isolated_particles",
        "fluidsurf:source",          "fluidsurf:version"};
}

} // namespace fluidsurf
