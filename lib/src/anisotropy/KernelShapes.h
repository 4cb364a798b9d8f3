// KernelShapes.h - Yu and Turk's anisotropic kernels ([YT10]: "Reconstructing surfaces of
// particle-based fluids using anisotropic kernels", 2013; thesis §4.4) for the particles at the
// surface: each kernel's support becomes an ellipsoid that follows its neighbourhood, flat on a
// flat face and long along a thin jet, and its centre moves towards its neighbours' mean.
//
// Per surface or splash particle i, with neighbours j within the PCA radius a (self included)
// and weights w_ij = 1 - (|x_i - x_j| / a)^3:
//   mean      m_i = sum w_ij x_j / sum w_ij
//   spread    C_i = sum w_ij (x_j - m_i)(x_j - m_i)^T / sum w_ij = R diag(s1 >= s2 >= s3) R^T
//   clamped   t_k = max(s_k, s1 / k_r)            (no axis shorter than a k_r-th of the longest)
//   axes      e_k = R_inf t_k / t3               (the shortest axis R_inf, the others longer)
//   shape     G_i = R diag(1 / e_k) R^T          (|G_i d| < 1: offset d inside the support)
//   centre    c_i = (1 - lambda) x_i + lambda m_i
// A particle with fewer than N_eps neighbours (other than itself) keeps the sphere, G_i =
// I / (k_n R_inf), and its centre. Interior particles keep both: the thesis notes that stretching
// them is wasted work, and what they add to the field near the surface is smooth already.
//
// Where YT10 scale the clamped spread by k_s = 1400 (a constant for their scenes' units), the
// axes here are scaled so that the shortest is the isotropic kernel's R_inf: the same for any
// unit of length, and kernels only grow, along the surface. Scaled to the sphere's volume
// instead (so the normal axis shrinks below R_inf), a face particle's kernel no longer reached
// the layer beneath it, and the gap became cavities (two in a jittered slab at k_r = 4) and
// broke thin sheets. The support (what the gather must cover) is at most k_r R_inf.
#pragma once

#include "classify/Classify.h"
#include "neighbors/CellIndex.h"

#include <fluidsurf/Context.h>
#include <fluidsurf/Params.h>
#include <fluidsurf/Vec3.h>

#include <cstddef>
#include <vector>

namespace fluidsurf {
namespace anisotropy {

/// (The defaults are [YT10]'s; the pipeline's come from Params through shapeParams.)
struct ShapeParams
{
    double influenceRadius = 0; ///< R_inf: the isotropic kernel's radius, world units
    double pcaRadius = 0;       ///< a: the PCA's neighbourhood radius, world units
    double maxAxisRatio = 4;    ///< k_r: longest axis over shortest, at most (>= 1)
    int minNeighbours = 25;     ///< N_eps: fewer neighbours (self aside) keep the sphere
    double sparseScale = 1;     ///< k_n: the sphere's radius for those, in R_inf
    double centreSmoothing =
        0.9; ///< lambda: how far a centre moves to its neighbours' mean, [0, 1]
};

/// The pipeline's: Params' anisotropy fields (Params.h), R_inf = influenceRadius.
ShapeParams shapeParams(const Params& params);

/// The most a kernel reaches from its centre along any direction, in R_inf: what the gather must
/// cover (k_r, or k_n when larger).
double maxReach(const ShapeParams& params);

struct KernelShapes
{
    /// per particle in the index's order: G as (xx, xy, xz, yy, yz, zz)
    util::NoInitVector<float> shapes;
    util::NoInitVector<Vec3f> centres; ///< per particle in the index's order
    size_t stretched = 0;              ///< particles given an ellipsoid
    size_t sparse = 0;                 ///< surface particles with fewer than N_eps neighbours
};

/// Shapes and centres of every particle of index (classes in index order, as classifyParticles
/// gives them). The index's cells may be of any size. Parallel over particles; ctx.checkpoint()
/// per range; the same result for any thread count. ValueError for invalid params.
KernelShapes kernelShapes(const neighbors::CellIndex& index,
                          const classify::Classification& classes, const ShapeParams& params,
                          Context& ctx);

/// The field's particles: the kernels' centres indexed anew (cells of cellSize; radii as the
/// index had them), isolated ones left out unless kept, with each one's G in that index's order.
struct KernelParticles
{
    neighbors::CellIndex centres;
    util::NoInitVector<float> shapes; ///< 6 a particle, in centres' order
};
KernelParticles kernelParticles(const neighbors::CellIndex& index,
                                const classify::Classification& classes, const KernelShapes& shapes,
                                bool keepIsolated, double cellSize, Context& ctx);

/// kernelParticles where every centre is its particle's position (lambda = 0): the index itself,
/// moved in, less its isolated particles unless kept (in place, in order: no second index).
KernelParticles kernelParticles(neighbors::CellIndex&& index,
                                const classify::Classification& classes, const KernelShapes& shapes,
                                bool keepIsolated);

} // namespace anisotropy
} // namespace fluidsurf
