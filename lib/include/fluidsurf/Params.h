// Params.h - every parameter of the reconstruction pipeline in one documented struct.
//
// Lengths are world units (those of the particle positions). Defaults are multiples of the
// particle radius r = half the rest spacing (DESIGN.md, "Conventions"); build a consistent set
// with Params::fromRadius(r) and change single fields afterwards. The CLI takes the same values
// relative to r (`--voxel 1.0` means voxelSize = 1 * r).
#pragma once

#include <fluidsurf/Level.h>

#include <string>

namespace fluidsurf {

/// Which scalar field is evaluated at the grid vertices.
enum class FieldKind {
    Ssp07, ///< Solenthaler et al. 2007: phi = |x - xbar| - rbar * f(EV_max of grad xbar)
    Zb05,  ///< Zhu & Bridson 2005: the same with f == 1 (faster, blobs in concave regions)
    /// SSP07 with [YT10]'s anisotropic kernels (issue 64): each surface particle's kernel
    /// stretched along the fluid's surface, from the PCA of its neighbours
    /// (anisotropy/KernelShapes.h, field/AnisotropicField.h); flatter faces. Narrow band only,
    /// not adaptive; the kernels' shapes are made on the CPU, the gather runs on either device.
    Ssp07Aniso,
    /// Yu & Turk's [YT10] density field (thesis §4.4) with the same kernels: phi = (isoLevel -
    /// sum_j V_j W(x - c_j, G_j)) R, V_j = (2 r_j)^3, W = 315 / (64 pi) det(G) (1 - |G d|^2)^3
    /// (normalised: about 1 inside the fluid). A density difference scaled by R, not a distance.
    /// Narrow band only, not adaptive.
    Yt10
};

/// Whether the field takes each particle's kernel shape (anisotropy/KernelShapes.h).
inline bool isAnisotropic(FieldKind f)
{
    return f == FieldKind::Ssp07Aniso || f == FieldKind::Yt10;
}

/// How the field is computed. All three give the same field (up to float rounding for
/// Scatter); they differ in cost and memory, which is what the thesis' Tables 4.4/4.5 compare.
enum class FieldMethod {
    NarrowBand, ///< thesis ch. 4: only vertices near surface particles, parallel gather
    GatherFull, ///< baseline: parallel gather at every vertex of the bounding volume
    Scatter     ///< baseline: serial, particles add to every vertex of the bounding volume
};

struct Params
{
    double radius = 0;          ///< r: particle radius, half the rest spacing
    double voxelSize = 0;       ///< dx: grid (Marching Cubes cell) size; default r
    double influenceRadius = 0; ///< R: support of the field kernel; default 4r
    double smoothingLength = 0; ///< h: SPH support for neighbour counts/color field; default 4r
    double bandWidth = 0;       ///< narrow band half width per axis around surface particles;
                                ///< default 2r (at least r + voxelSize is used, see NarrowBand.h)
    double tLow = 0.4;          ///< EV_max below this: f = 1 (eq. 4.2)
    double tHigh = 3.5;         ///< EV_max at or above this: f = 0 (eq. 4.3, clamped)
    /// phi = |x - xbar| - radiusScale * rbar * f: 1 is SSP07 as published. Its surface lies
    /// 0.87 r above a flat lattice face's particle centres, not r, so a block encloses 5% less
    /// than its particles' N (2r)^3; 1.096 puts that face at r (issue 64). [0.5, 2].
    double radiusScale = 1.0;
    int surfaceNeighbours = 25; ///< fewer neighbours within h: surface particle (thesis 4.2.2)
    int splashNeighbours = 3;   ///< fewer neighbours within h: splash particle (ch. 6)
    double colorFieldThreshold = 0.9;     ///< color field (eq. 4.6) below this: surface particle;
                                          ///< ~1.0 inside the fluid, ~0.82 on a flat lattice face
    double colorGradientThreshold = 0.45; ///< |grad cf| * h above this: surface particle;
                                          ///< 0 inside, 0.62 on a flat lattice face
    double halfWidth = 3;                 ///< level-set background = halfWidth * voxelSize
    bool perParticleRadii = true;         ///< use a radius attribute (pscale) as r_j when present
    bool keepIsolated = false; ///< isolated particles join the field as spheres of radius r
                               ///< (default: left out of the grid and reported)
    FieldKind field = FieldKind::Ssp07;
    /// Yt10: the density the surface passes through, (0, 1): 0.5 puts a flat lattice face r
    /// above its particles' centres, where their volumes end.
    double isoLevel = 0.5;
    /// Ssp07Aniso, Yt10: a kernel's longest axis over its shortest (which stays R) at most, k_r of
    /// [YT10]; 1 gives SSP07's field. 1.5 left no more components than SSP07 on every real frame;
    /// 1.75 and 2 made a jittered slab flatter still, but split thin sheets off (issue 64).
    double anisotropyRatio = 1.5;
    /// Ssp07Aniso, Yt10: the radius of each particle's PCA; default 8r (2h, as [YT10]: within h a
    /// particle of a flat face has about 17 neighbours, too few for a stable PCA).
    double anisotropyRadius = 0;
    /// Ssp07Aniso, Yt10: a particle with fewer neighbours within anisotropyRadius keeps the sphere
    /// (N_eps of [YT10]).
    int anisotropyNeighbours = 25;
    /// Ssp07Aniso, Yt10: how far a surface particle's kernel centre moves to its neighbours'
    /// weighted mean, lambda of [YT10], [0, 1]. Theirs, 0.9, took a jittered slab's top face below
    /// its particles' centres; 0.1 made it bumpier than 0 (issue 64).
    double centreSmoothing = 0;
    FieldMethod method = FieldMethod::NarrowBand;
    /// The curvature-adaptive 3-level grid of thesis chapter 6 (fluidsurf/AdaptiveGrid.h):
    /// voxelSize becomes the finest level (3); flat parts of the surface are sampled at
    /// 2 * voxelSize. Narrow-band method only.
    bool adaptive = false;
    /// Mean particle curvature kappa (thesis eq. 6.1-6.3) at and above which a coarse cell is
    /// refined to the finest level; dimensionless (see adaptive/Curvature.h).
    double curvatureThreshold = 3.0;
    /// Also refined: a flat cell whose surface would move by more than this many finest voxels
    /// if the field, probed at the finest level where the cell's surface is, replaced what the
    /// level-2 grid interpolates there. 0: curvature alone decides, as in the thesis. 0.3 keeps
    /// every real frame within 0.33 r of the uniform mesh and takes the generated 1M drop to 38%
    /// of its triangles; 0.4 keeps them within 0.45 r, 0.5 not within 0.5 r (BENCHMARKS.md).
    /// Either way, level-2 cells more of whose neighbours are at level 3 than at level 2 are
    /// refined too (adaptive/LevelMap.h: they would cost more crack triangles than they save).
    double levelTolerance = 0.3;
    /// Also refined: cells near a particle with fewer neighbours within h than this - one-layer
    /// sheets, jets and droplets (8-12 neighbours in a flat layer, 32 inside the fluid), which
    /// the coarser level can lose whole. The thesis refines near splash particles
    /// (splashNeighbours) only; this is never below that.
    int thinNeighbours = 13;

    /// The DESIGN.md defaults for particle radius r.
    static Params fromRadius(double r);

    /// Throws ValueError naming the first invalid field.
    void validate() const;

    /// The grid of the field's finest (today: only) level.
    Level level() const { return Level{voxelSize}; }
    /// Level-set background at a level: halfWidth voxels of it.
    double background(const Level& l) const { return halfWidth * l.voxelSize; }
    double background() const { return background(level()); }
};

const char* fieldName(FieldKind f);                  ///< "ssp07", "zb05", "ssp07-aniso", "yt10"
const char* methodName(FieldMethod m);               ///< "narrow-band", "gather-full", "scatter"
FieldKind fieldFromName(const std::string& name);    ///< ValueError for unknown names
FieldMethod methodFromName(const std::string& name); ///< ValueError for unknown names

} // namespace fluidsurf
