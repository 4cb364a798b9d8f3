// LevelFields.h - phi at the points each level needs (thesis §6.2.2), each evaluated once, and
// the sub-sampled values on the faces between levels (§6.2.3, "Scalar field continuity").
//
// The thesis kept the points in hash maps keyed by their level-3 id (eq. 6.4-6.6); here the
// levels are VDB trees in one index space (Levels.h), evaluated through the backend's evaluator
// (the CPU gather or the GPU), never the field stage's internals:
//  - level 2 (2 dx): the corners of every 2 dx cell of every meshed coarse cell, the band's
//    values where it has them, evaluated where not;
//  - level 3 (dx): every point of every level-3 cell: level-2 points copied from level 2,
//    points on a face or edge shared with a level-2 cell sub-sampled from level 2, the rest
//    evaluated.
// Completion: where a level-3 cell has a sign change on an edge of its boundary and a cell
// sharing that edge is not meshed, that cell is added at level 3 and evaluated, repeated until
// nothing is added (the level-2 band is complete already: CompleteBand.h). Parallel over cells
// and leaves; deterministic.
#pragma once

#include "adaptive/Levels.h"
#include "field/CompleteBand.h"

#include <fluidsurf/Context.h>

#include <openvdb/openvdb.h>

namespace fluidsurf {
namespace adaptive {

struct LevelFieldStats
{
    size_t level2Evaluated = 0; ///< level-2 points evaluated here (beyond the band)
    size_t level3Evaluated = 0; ///< level-3 points evaluated
    size_t subsampled = 0;      ///< level-3 points sub-sampled from level 2
    size_t completionCells = 0; ///< coarse cells added by completion (level 3)
    size_t probes = 0;          ///< level-3 probes of level-2 cells (tolerance > 0)
    size_t refinedCells = 0;    ///< level-2 cells the probes moved to level 3
    size_t islandCells = 0;     ///< level-2 cells moved to level 3 as islands (LevelMap.h)
    size_t crossingProbes = 0;  ///< probes kept in level 3 to place level-2 vertices
};

/// Which level-2 cells move to level 3 before level 3 is filled (beyond the level map's own).
struct Refinement
{
    float tolerance = 0;      ///< world units; 0: none by probes
    bool closeIslands = true; ///< level-2 islands among level 3 join it (LevelMap.h)
};

/// Fills level2 (grows) and returns the level-3 tree (background background3); levels grows by
/// the refinement's and the completion's cells. With a tolerance > 0, a level-2 cell is first
/// probed at level 3 where its surface is (the middle of every level-2 edge and the centre of
/// every level-2 cell with a sign change, and the centre of each of its faces with one), and
/// moves to level 3 where its surface would move by more than the tolerance: on an edge, the
/// crossing's own move from the level-2 edge to the level-3 half-edge; at a centre, phi's change
/// over its gradient. The probes' values are kept for the cells that end up at level 3. Then,
/// with closeIslands, level-2 islands among level 3 join it (closeLevel2Islands, LevelMap.h).
/// The probes at the middle of level-2 edges that no level-3 cell touches in the end stay in
/// the level-3 tree: the mesher places those edges' crossings with them (on the level-3
/// half-edge, where the uniform mesh of dx has its vertex), not by level 2's linear guess.
openvdb::FloatTree::Ptr fillLevels(openvdb::FloatTree& level2, LevelTree& levels,
                                   const field::FieldEvaluator& evaluate2,
                                   const field::FieldEvaluator& evaluate3, float background3,
                                   const Refinement& refinement, Context& ctx,
                                   LevelFieldStats* stats = nullptr);

} // namespace adaptive
} // namespace fluidsurf
