// LevelSet.h - the last stage: field values on a tree -> a proper OpenVDB level set grid
// (sign flood fill, pruning, class, name, the level's transform, metadata). Writing it is
// io/LevelSetIO.h's work.
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/Level.h>
#include <fluidsurf/Params.h>

#include <openvdb/openvdb.h>

#include <string>

namespace fluidsurf {
namespace levelset {

struct GridInfo
{
    size_t particles = 0, isolated = 0;
    std::string source;
};

/// Turn a tree of clamped field values into the "surface" level-set grid. With
/// keepOnlyBand, voxels whose |phi| reached the background are deactivated first (the
/// volume methods activate every vertex; the narrow band keeps its band; ctx.checkpoint() every
/// 64 leaves). Sign flood fill and pruning are OpenVDB's, without an interrupter.
openvdb::FloatGrid::Ptr finishLevelSet(openvdb::FloatTree::Ptr tree, const Params& params,
                                       const Level& level, bool keepOnlyBand, const GridInfo& info,
                                       Context& ctx);

} // namespace levelset
} // namespace fluidsurf
