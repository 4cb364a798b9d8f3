// Classify.h - particle classification (thesis §4.2.2, §5.2.3, §6.2): which particles seed the
// narrow band and which take part in the field at all.
//
// For every particle: the number of other particles closer than h and the smoothed color field
// (eq. 4.6) cf_i = sum_j V_j W(|x_i - x_j|, h), self included, with the poly6 kernel
// W(d, h) = 315 / (64 pi h^9) (h^2 - d^2)^3 and the rest volume V_j = (2 r_j)^3 standing in for
// m_j / rho_j (frames rarely carry masses). cf is ~1.0 inside the fluid; on a flat lattice face
// it is 0.82 and on the layer below exactly the interior value, because the kernel's support h
// = 4r reaches two spacings. The color field alone misses surfaces where the simulator packs
// particles densely (fluid against a wall: cf >= 1 on the free side too), so its gradient
// (MCG03's surface normal), scaled by h, is tested as well: 0 inside, 0.62 on a lattice face.
// Classes:
//   isolated  no neighbour within h (left out of the field; later rendered as spheres)
//   splash    1 or 2 neighbours (< splashNeighbours): surface, and finest level in ch. 6
//   surface   cf < colorFieldThreshold, |grad cf| h > colorGradientThreshold, or fewer than
//             surfaceNeighbours neighbours
//   interior  everything else
#pragma once

#include "classify/ClassRule.h"
#include "neighbors/CellIndex.h"

#include <fluidsurf/Params.h>

#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace classify {

inline bool isSurface(uint8_t c)
{
    return c == Surface || c == Splash;
}

struct Classification
{
    // (not zeroed first: classifyParticles writes every particle's, on all threads)
    util::NoInitVector<uint8_t> classes; ///< per particle, in the index's cell order
    /// The sums, per particle (only with Outputs::sums; else empty)
    util::NoInitVector<uint32_t> neighbours; ///< other particles closer than h
    util::NoInitVector<float> colorField;    ///< cf_i as above
    util::NoInitVector<float> colorGradient; ///< |grad cf_i| * h (MCG03's surface normal length)
    /// -grad cf_i / |grad cf_i| (outward; 0 where the gradient vanishes), for the surface and
    /// splash particles only, and only when asked for (the curvature of ch. 6); else empty
    std::vector<Vec3f> normals;
    size_t interior = 0, surface = 0, splash = 0, isolated = 0; ///< surface excludes splash
};

/// The kernel constants, computed once here for the CPU and the CUDA classification alike (the
/// two must round identically).
struct KernelConstants
{
    double h = 0;             ///< smoothing length
    float h2 = 0;             ///< float(h * h)
    double poly6 = 0;         ///< 315 / (64 pi h^9)
    double gradientScale = 0; ///< 6 poly6 h: |grad cf| h = gradientScale |sum V t^2 d|
    double uniformVolume = 0; ///< (2r)^3
};
KernelConstants kernelConstants(const Params& params);

/// The class rule's constants and thresholds from the parameters.
ClassRule classRule(const Params& params);

/// The floats per register that classification's kClassLanes lanes run in by default: 8 (one
/// AVX register) where the CPU has AVX2, else 4 (two SSE registers). The sums are the same bits
/// either way, and the device's.
int classifyRegisterLanes();

/// What classifyParticles fills besides the classes. The pipeline's field needs the classes
/// alone; the sums cost 12 bytes a particle written and given back (on the 13.1M drop, 157 MB
/// of fresh pages, a tenth of the frame's page faults).
struct Outputs
{
    bool sums = false;    ///< neighbours, colorField and colorGradient (else left empty)
    bool normals = false; ///< normals (the curvature of ch. 6)
};

/// Parallel over occupied cells (ctx.checkpoint() per range); each cell gathers its
/// neighbourhood once.
/// uniformRadius is used when the index has no per-particle radii.
/// `registerLanes`: 4, or 8 where classifyRegisterLanes() is 8 (tests run both); ValueError
/// otherwise.
Classification classifyParticles(const neighbors::CellIndex& index, const Params& params,
                                 Context& ctx, Outputs outputs = {},
                                 int registerLanes = classifyRegisterLanes());

/// The marks (index order) of the particles that are not isolated: those the field takes.
std::vector<uint8_t> notIsolated(const Classification& classes);

/// The classification of the particles keep marks (index order, as neighbors::keepParticles
/// keeps them), compacted in place; the class counts stay those of the whole frame.
void selectClasses(Classification& classes, const std::vector<uint8_t>& keep);

/// v's elements that keep marks, in order, compacted in place (capacity given back).
template <typename Vector> void selectInPlace(Vector& v, const std::vector<uint8_t>& keep)
{
    if (v.empty()) return;
    size_t n = 0;
    for (size_t i = 0; i < v.size(); ++i)
        if (keep[i]) v[n++] = v[i];
    v.resize(n);
    v.shrink_to_fit();
}

} // namespace classify
} // namespace fluidsurf
