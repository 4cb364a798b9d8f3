// ScatterField.h - the thesis' serial "scatter" baseline (§4.2.3, Tables 4.4/4.5): one pass over
// the particles, each adding its kernel sums to every vertex within R, in dense arrays over the
// bounding volume; then phi at every vertex. Memory and time scale with the volume: this exists
// to be compared against, not to be used.
#pragma once

#include "neighbors/CellIndex.h"

#include <fluidsurf/Context.h>
#include <fluidsurf/Level.h>
#include <fluidsurf/Params.h>

#include <openvdb/openvdb.h>

namespace fluidsurf {
namespace field {

/// A tree whose active voxels are the vertices of the bounding volume with |phi| < background.
/// ValueError (before allocating) when the dense arrays would not fit in memory. Serial: one
/// ctx.checkpoint() per 4096 particles.
openvdb::FloatTree::Ptr scatterField(const neighbors::CellIndex& particles, const Params& params,
                                     const Level& level, Context& ctx,
                                     size_t* evaluations = nullptr);

} // namespace field
} // namespace fluidsurf
