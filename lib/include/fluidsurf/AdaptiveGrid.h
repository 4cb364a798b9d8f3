// AdaptiveGrid.h - the curvature-adaptive 3-level grid of thesis chapter 6 as VDB grids, and its
// mesher.
//
// Levels. The frame is covered by coarse cells of 4 dx (level 1; dx = Params::voxelSize, r by
// default). Coarse cells the surface passes through are refined once (level 2, cells of 2 dx)
// where the surface is flat, twice (level 3, cells of dx) where it is curved or splashes.
//
// Mapping onto VDB. VDB's tree levels branch 8, 16 and 32 per axis, not 2, so the levels are
// separate grids sharing one index space, as OpenVDB's MultiResGrid does: a level-3 index is
// twice the level-2 index of the same point and four times the coarse index. Each grid is an
// ordinary VDB grid that any VDB tool opens:
//   "surface"       FloatGrid, level set, voxel 2 dx: the whole surface at level 2 (a complete
//                   narrow-band level set of its own, the coarse preview)
//   "surface_fine"  FloatGrid, level set, voxel dx: every grid point of the level-3 cells, and
//                   the field at the middle of each level-2 edge the surface crosses away from
//                   level 3 (it places that edge's vertex where the uniform mesh of dx has it)
//   "levels"        Int32Grid, voxel 4 dx: per coarse cell that is meshed, its level (2 or 3);
//                   cell (I,J,K) spans the level-3 points 4I..4I+4 along each axis
// Values on a face (or edge) that a level-3 cell shares with a level-2 cell are not the field's
// but sub-sampled from the level-2 values (thesis Fig. 6.4): linear along a level-2 edge,
// bilinear (the mean of four) at a level-2 face centre. Both sides then see the same function on
// that face, so their crossings on its outer edges coincide and the remaining cracks are small
// planar polygons, closed by merging level-3 points into level-2 crossings or by patch
// triangles (§6.2.3).
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/Mesh.h>

#include <openvdb/openvdb.h>

#include <cstddef>
#include <string>

namespace fluidsurf {

struct AdaptiveGrid
{
    openvdb::FloatGrid::Ptr level2; ///< "surface", voxel 2 dx
    openvdb::FloatGrid::Ptr level3; ///< "surface_fine", voxel dx
    openvdb::Int32Grid::Ptr levels; ///< "levels", voxel 4 dx, values 2 or 3

    static constexpr const char* kLevel2Name = "surface";
    static constexpr const char* kLevel3Name = "surface_fine";
    static constexpr const char* kLevelsName = "levels";

    bool empty() const { return !level2; }
    /// The three grids, in the order above (for io::writeLevelSet).
    openvdb::GridPtrVec grids() const;
    /// The adaptive grid among grids read from a .vdb: the three names above with voxel sizes 2:1
    /// and 4:1. Empty when "levels" is absent (an ordinary level set); InputError naming source
    /// when it is there but the other grids are missing or do not fit.
    static AdaptiveGrid fromGrids(const openvdb::GridPtrVec& grids, const std::string& source);
};

struct AdaptiveMeshStats
{
    size_t level2Cells = 0, level3Cells = 0;         ///< coarse cells meshed at each level
    size_t level2Triangles = 0, level3Triangles = 0; ///< from the cells of each level
    size_t patchTriangles = 0;                       ///< closing the cracks (§6.2.3)
    /// Level-3 points of cracks merged into the crossings of their level-2 edge, closing those
    /// cracks with no triangle added (adaptive/CollapseCracks.h); each takes one level-3
    /// triangle away.
    size_t mergedCrackPoints = 0;
    /// Cracks that could not be closed (their edges did not form loops); 0 unless the grids
    /// were changed by hand. The mesh then has boundary edges there.
    size_t openCracks = 0;
};

struct AdaptiveMeshOptions
{
    /// Close a crack with one level-2 edge by merging its level-3 points into that edge's ends
    /// where the mesh stays manifold and unfolded (fewer triangles, no slivers); false: always
    /// cut the level-2 triangle at them (one triangle more per point), as the thesis patches.
    bool mergeCrackPoints = true;
};

/// One indexed mesh of the zero crossing: marching cubes in every level-2 cell at 2 dx and
/// every level-3 cell at dx, sharing the vertices of their common edges, with the cracks
/// between levels closed (merged points, cut triangles, patch fans). Closed and manifold
/// wherever the uniform mesher's is; counter-clockwise seen from outside; angle-weighted vertex
/// normals. Parallel over coarse cells (ctx.checkpoint() per range), identical for any thread
/// count. Timed as "mesh".
TriangleMesh meshAdaptiveGrid(const AdaptiveGrid& grid, Context& ctx,
                              AdaptiveMeshStats* stats = nullptr,
                              const AdaptiveMeshOptions& options = {});

} // namespace fluidsurf
