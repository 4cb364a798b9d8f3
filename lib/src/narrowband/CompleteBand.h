// CompleteBand.h - closing the narrow band around every zero crossing it touches.
//
// The thesis' band (vertices within 2r of surface particles) holds the surface where the fluid is
// flat or convex. In concave pockets and between splashes the centroid xbar of SSP07 sits in the
// gap, and the zero crossing can lie more than 2r from every surface particle: gather-full then
// shows a sign change between a band vertex and a vertex outside the band, where Marching Cubes
// would leave a hole. This stage grows the band there, and only there: every inactive axis
// neighbour of an active voxel with |phi| < 0.5 voxel, and every inactive voxel of the 3x3x3
// block around a voxel with a sign change to an active neighbour (marching cubes triangulates
// only cells whose 8 corners are active), is activated and evaluated, repeated until nothing is
// added (a few rounds; the cost is a small fraction of the band).
#pragma once

#include "neighbors/CellIndex.h"

#include <fluidsurf/Params.h>

#include <openvdb/openvdb.h>

#include <functional>

namespace fluidsurf {
namespace narrowband {

/// Fills every active voxel of a tree with phi (the CPU gather, or the GPU's).
using FieldEvaluator = std::function<void(openvdb::FloatTree&)>;

/// Returns the number of voxels added (and evaluated by evaluate).
size_t completeBand(openvdb::FloatTree& tree, const Params& params, const FieldEvaluator& evaluate);

/// The same with the CPU gather over particles.
size_t completeBand(openvdb::FloatTree& tree, const neighbors::CellIndex& particles,
                    const Params& params);

} // namespace narrowband
} // namespace fluidsurf
