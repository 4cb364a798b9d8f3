// AnisotropicField.h - the SSP07 field with anisotropic kernels (issue 64, "beyond the thesis"):
// each particle's weight is the SSP07 kernel of its stretched offset, w_j = (1 - |G_j (x -
// c_j)|^2)^3 with c_j and G_j from anisotropy/KernelShapes.h, and x-bar, r-bar and the
// f-correction follow as in FieldValue.h: grad w_j = 6 t_j^2 A_j d_j with A_j = G_j^2 and d_j =
// c_j - x, so J = grad x-bar = (6 / W) (sum t_j^2 d_j (A_j d_j)^T - (D / W) (sum t_j^2 A_j d_j)^T),
// of which FieldMath's fieldValue needs the symmetric part. With G_j = I / R every sum is
// FieldValue.h's. For Yt10 ([YT10]'s density, Params.h) the same gather sums V_j W in the radius
// slot and FieldMath turns the sum into phi. Parallel over leaves; each voxel's sums in float,
// kernel after kernel in the cell index's order (AnisotropicSums.h), so the bits do not depend on
// the thread count.
#pragma once

#include "anisotropy/KernelShapes.h"
#include "neighbors/CellIndex.h"

#include <fluidsurf/Context.h>
#include <fluidsurf/Level.h>
#include <fluidsurf/Params.h>

#include <openvdb/openvdb.h>

#include <vector>

namespace fluidsurf {
namespace field {

/// The field's kernels and what the gather needs of each, made once a frame (the band's
/// completion evaluates again and again): the centres (indexed: centres.positions are the c_j,
/// centres.radii their radii or empty) and, in their order,
struct AnisotropicKernels
{
    const neighbors::CellIndex* centres = nullptr;
    std::vector<float> a;       ///< A' = R^2 G^2 (xx, xy, xz, yy, yz, zz): I for a sphere of R
    std::vector<float> extent;  ///< the box's half extents sqrt((G^-2)_aa), world units
    std::vector<float> stretch; ///< at least the root of A''s largest eigenvalue (1: a sphere of R)
    /// Yt10 (else empty): V_j 315 / (64 pi) det(G_j), the density kernel's factor, V_j = (2 r_j)^3
    std::vector<float> weight;
    double reach = 0; ///< the most any kernel reaches, world units
};

/// From shapes[6 j ..], the G of centres' particle j (anisotropy::KernelParticles), and R =
/// params.influenceRadius (and r_j = centres.radii or params.radius, for Yt10). reach: the most
/// any kernel reaches (anisotropy::maxReach R).
AnisotropicKernels anisotropicKernels(const neighbors::CellIndex& centres, const float* shapes,
                                      double reach, const Params& params);

/// phi at every active voxel of tree (clamped to +-background); one ctx.checkpoint() per leaf
/// range. Returns the number of evaluations.
size_t evaluateAnisotropicField(openvdb::FloatTree& tree, const AnisotropicKernels& kernels,
                                const Params& params, const Level& level, Context& ctx);

namespace detail {
/// evaluateAnisotropicField with eight voxels a register (wide: AVX2 and FMA, the default where
/// fieldLanes() is 8) or one voxel at a time on one float: the same bits (tests run both).
/// ValueError for wide without AVX2 and FMA.
size_t evaluateAnisotropicField(openvdb::FloatTree& tree, const AnisotropicKernels& kernels,
                                const Params& params, const Level& level, Context& ctx, bool wide);
} // namespace detail

} // namespace field
} // namespace fluidsurf
