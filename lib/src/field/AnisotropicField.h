// AnisotropicField.h - the SSP07 field with anisotropic kernels (issue 64, "beyond the thesis"):
// each particle's weight is the SSP07 kernel of its stretched offset, w_j = (1 - |G_j (x -
// c_j)|^2)^3 with c_j and G_j from anisotropy/KernelShapes.h, and x-bar, r-bar and the
// f-correction follow as in FieldValue.h: grad w_j = 6 t_j^2 A_j d_j with A_j = G_j^2 and d_j =
// c_j - x, so J = grad x-bar = (6 / W) (sum t_j^2 d_j (A_j d_j)^T - (D / W) (sum t_j^2 A_j d_j)^T),
// of which FieldMath's fieldValue needs the symmetric part. With G_j = I / R every sum is
// FieldValue.h's. A scalar gather per leaf (the first version: correctness before speed).
#pragma once

#include "anisotropy/KernelShapes.h"
#include "neighbors/CellIndex.h"

#include <fluidsurf/Context.h>
#include <fluidsurf/Level.h>
#include <fluidsurf/Params.h>

#include <openvdb/openvdb.h>

namespace fluidsurf {
namespace field {

/// phi at every active voxel of tree (clamped to +-background), from the particles of centres
/// (indexed: centres.positions are the kernels' centres c_j, centres.radii their radii or empty)
/// with shapes[6 j ..] the G of centres' particle j (in centres' order). reach: the most any
/// kernel reaches, world units. Returns the number of evaluations.
size_t evaluateAnisotropicField(openvdb::FloatTree& tree, const neighbors::CellIndex& centres,
                                const float* shapes, double reach, const Params& params,
                                const Level& level, Context& ctx);

} // namespace field
} // namespace fluidsurf
