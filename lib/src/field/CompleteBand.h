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
// It belongs to the field stage because it evaluates the field: the new voxels are handed to an
// evaluator, the backend's (the CPU gather or the GPU's), never to a stage's internals.
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/Level.h>

#include <openvdb/openvdb.h>

#include <functional>

namespace fluidsurf {
namespace field {

/// Fills every active voxel of a tree with phi (Backend::evaluate).
using FieldEvaluator = std::function<void(openvdb::FloatTree&)>;

/// Returns the number of voxels added (and evaluated by evaluate). The frontier scan is parallel
/// over leaf ranges with one ctx.checkpoint() each.
size_t completeBand(openvdb::FloatTree& tree, const Level& level, const FieldEvaluator& evaluate,
                    Context& ctx);

} // namespace field
} // namespace fluidsurf
