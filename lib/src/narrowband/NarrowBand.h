// NarrowBand.h - which grid vertices get a field value (thesis §4.2.2, "Extracting surface
// vertices"): every vertex within +-w per axis of a surface particle, as VDB topology.
//
// w = max(bandWidth, r_max + dx), dx the level's voxel size. The field's zero crossing lies at most
// ~r beyond the outer particle centres, and a Marching Cubes cell it crosses has corners up to one
// voxel further: r + dx covers them. At the default voxel r this is the thesis' 2r; at voxel 2r the
// thesis' band would leave gaps in the cells the surface crosses.
//
// Also the topology of the baselines: every vertex of the bounding volume (particles +- R).
#pragma once

#include "classify/Classify.h"
#include "neighbors/CellIndex.h"

#include <fluidsurf/Context.h>
#include <fluidsurf/Level.h>
#include <fluidsurf/Params.h>

#include <openvdb/openvdb.h>

namespace fluidsurf {
namespace narrowband {

/// The half width w used for particles of radius up to maxRadius.
double effectiveBandWidth(const Params& params, const Level& level, double maxRadius);

/// Active voxels within +-width of the surface and splash particles, and of isolated ones with
/// params.keepIsolated (parallel, deterministic; ctx.checkpoint() per range). width comes from
/// effectiveBandWidth.
openvdb::MaskTree::Ptr buildNarrowBand(const neighbors::CellIndex& particles,
                                       const classify::Classification& classes,
                                       const Params& params, const Level& level, double width,
                                       Context& ctx);

/// ValueError with the estimate, past ctx's memory budget, for a band of `seeds` surface
/// particles (each adds at most its box of voxels, as a rule its share of the surface, a
/// spacing squared, times the band's thickness). buildNarrowBand calls it; so does the GPU's
/// band, from its classes' counts.
void requireBandMemory(size_t seeds, const Params& params, const Level& level, double width,
                       Context& ctx);

/// Index box of every vertex within R of the particles' bounding box (the "bounding volume").
openvdb::CoordBBox boundingVolume(const neighbors::CellIndex& particles, const Params& params,
                                  const Level& level);

/// Estimated bytes of a dense grid over the bounding volume with bytesPerVertex each; throws
/// ValueError naming the estimate when it exceeds the machine's physical memory.
double checkDenseMemory(const openvdb::CoordBBox& box, double bytesPerVertex, const char* what);

} // namespace narrowband
} // namespace fluidsurf
