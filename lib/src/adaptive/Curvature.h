// Curvature.h - how curved the surface is at each surface particle (thesis §6.2.1, eq. 6.1-6.2,
// after [IAAT12]): kappa_i = sum_j (1 - n_i . n_j) k_c(|x_i - x_j|, h), k_c(d, h) = 1 - d / h
// for d <= h, over the other surface and splash particles j within h. n is the unit normal of
// the smoothed color field (MCG03): -grad cf_i, n_i ~ sum_j V_j (h^2 - d^2)^2 (x_i - x_j),
// which classification sums anyway (Classification::normals, asked for by the adaptive path).
//
// Interior particles take no part: their color-field gradient is near zero and its direction
// noise, which would make every surface particle next to them look curved. On a flat lattice face
// kappa is ~0; on a droplet of a few particles it is several units (the thesis' thresholds were
// 1.5 and 3).
#pragma once

#include "classify/Classify.h"
#include "neighbors/CellIndex.h"

#include <fluidsurf/Context.h>
#include <fluidsurf/Params.h>

#include <vector>

namespace fluidsurf {
namespace adaptive {

/// kappa per particle of the index (its cell order); 0 for interior and isolated particles.
/// classes must hold the normals (classifyParticles withNormals).
/// Parallel over particle ranges with a ctx.checkpoint() each; deterministic.
std::vector<float> particleCurvature(const neighbors::CellIndex& index,
                                     const classify::Classification& classes, const Params& params,
                                     Context& ctx);

} // namespace adaptive
} // namespace fluidsurf
