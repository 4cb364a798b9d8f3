// GatherField.h - the field stage (thesis §4.2.2, "Scalar value computation"): every active voxel
// of a FloatTree gathers all particles within R (surface and inner ones alike, so no double
// layer forms, thesis Fig. 4.2) and stores phi (FieldValue.h).
//
// Parallel over VDB leaves with TBB. Each leaf gathers its neighbourhood from the cell index once
// (the particles within R of the leaf's 8^3 voxels), sorts it into bins (z-slabs of one voxel,
// split by x and y), and then
// walks its voxel rows along z: a row keeps the particles within R of its (x, y) line, and a voxel
// reads the slabs within R of its z. The per-voxel sum has a fixed order and fixed lanes, so the
// output is bitwise identical for any thread count (on one machine: see fieldLanes()), and the same
// for the narrow band and for gather-full (both call this on their topology).
#pragma once

#include "field/FieldMath.h"
#include "neighbors/CellIndex.h"

#include <fluidsurf/Context.h>
#include <fluidsurf/Level.h>
#include <fluidsurf/Params.h>

#include <openvdb/openvdb.h>

#include <cstddef>
#include <cstdint>

namespace fluidsurf {
namespace field {

/// The lanes the sums run on by default: 8 where the CPU has AVX2 and FMA, else 4 (SSE2). The
/// lanes' partial sums add up in another order, so phi differs between the two in the last bits
/// (well within the field tests' 1e-5 r); one machine always takes the same. The CUDA gather
/// makes the 8-lane sums (cuda/facade/FieldGather.h).
int fieldLanes();

/// Fill every active voxel of tree (voxel (i,j,k) at (i,j,k) * level.voxelSize) with phi (one
/// ctx.checkpoint() per leaf range), clamped to +-background. Inactive voxels are left alone.
/// Returns the number of field evaluations. `lanes`: 4, or 8 where fieldLanes() is 8 (tests
/// run both); ValueError otherwise.
size_t evaluateField(openvdb::FloatTree& tree, const neighbors::CellIndex& particles,
                     const Params& params, const Level& level, Context& ctx,
                     int lanes = fieldLanes());

namespace detail {
/// evaluateField with the gather's particles read four at a time in AVX registers (wideGather,
/// the default where the CPU has AVX2) or one at a time: the same particles in the same order,
/// so the same bits (tests run both). ValueError for wideGather without AVX2.
size_t evaluateField(openvdb::FloatTree& tree, const neighbors::CellIndex& particles,
                     const Params& params, const Level& level, Context& ctx, int lanes,
                     bool wideGather);

/// One voxel's sums as the 8-lane gather makes them (for tests): candidates [b, e) of X, Y, Z
/// (and radii R, or null) in leaf-local coordinates, candidate j on lane (j - b) % 8, the voxel
/// at (vx, vy, vz); the arrays readable up to b + 8 ceil((e - b) / 8), lanes past e padded with
/// particles beyond R. ValueError where fieldLanes() is not 8.
FieldSums wideVoxelSums(const float* X, const float* Y, const float* Z, const float* R, uint32_t b,
                        uint32_t e, float vx, float vy, float vz, float invR2, bool ssp07);
} // namespace detail

} // namespace field
} // namespace fluidsurf
