// LevelMap.h - which coarse cells (4 dx) are meshed, and at which level (thesis §6.2, §6.2.1).
//
// Meshed cells: every coarse cell around an edge of the level-2 band (2 dx) whose ends change
// sign (all cells sharing the edge), and every cell holding a splash or thin particle (fewer
// than `thin` neighbours: a droplet, jet or one-layer sheet that level 2 may not resolve at all).
// The level fields' completion (LevelFields.h) then adds any cell the surface reaches beyond
// these, so the band at 2 dx needs no completion of its own.
// Level: 3 for a cell holding a splash or thin particle; otherwise the mean kappa (Curvature.h,
// eq. 6.3) of the surface particles within the band width of the cell decides, level 3 at or
// above the threshold, level 2 below. A meshed cell with no surface particle that near (the zero
// crossing of a concave pocket, CompleteBand.h) is level 3: nothing says it is flat.
// Islands: level-2 cells mostly surrounded by level 3 join it (closeLevel2Islands, run after the
// level fields' refinement).
#pragma once

#include "adaptive/Levels.h"
#include "classify/Classify.h"
#include "neighbors/CellIndex.h"

#include <fluidsurf/Context.h>
#include <fluidsurf/Level.h>
#include <fluidsurf/Params.h>

#include <openvdb/openvdb.h>

#include <vector>

namespace fluidsurf {
namespace adaptive {

struct LevelMapInput
{
    const openvdb::FloatTree& level2; ///< the completed band at 2 dx, with phi
    const neighbors::CellIndex& particles;
    const classify::Classification& classes; ///< in the index's cell order
    const std::vector<float>& kappa;         ///< particleCurvature, same order
    double dx = 0;                           ///< the finest voxel (level 3)
    double width = 0;                        ///< the band width at dx (effectiveBandWidth)
    double threshold = 0;                    ///< kappa at and above which a cell is level 3
    uint32_t thin = 0; ///< particles with fewer neighbours: level 3 around them (as splash)
};

/// The coarse cells (voxel 4 dx) with their levels as active values. Parallel, deterministic.
LevelTree::Ptr buildLevelMap(const LevelMapInput& in, Context& ctx);

/// Moves to level 3 every level-2 cell more of whose meshed face neighbours are at level 3 than
/// at level 2, in rounds (each round judged on the map before it) until none is left; returns
/// how many moved. Why: each level-2 square of a face between the levels that the surface
/// crosses costs at least one crack triangle (a sliver), and a level-2 cell hemmed in by level 3
/// has such faces on most sides while saving few triangles. Regions of level 2 stay: a cell on a
/// straight or convex border of one has at most as many level-3 neighbours as level-2 ones; a
/// strip one cell wide is taken from its ends. Level-3 and unmeshed cells never change.
size_t closeLevel2Islands(LevelTree& levels, Context& ctx);

} // namespace adaptive
} // namespace fluidsurf
