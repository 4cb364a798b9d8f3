// PostProcess.h - mesh post-processing (thesis chapter 5) on any triangle mesh: quadric-error
// decimation, smoothing, then Loop subdivision; the result carries the angle-weighted normals of
// its own surface (computed once, after the last step: no step reads them). reconstruct()
// runs it on the surface it meshed and then adds isolated particles as spheres (they need the
// particles); `fluidsurf post` runs it on a mesh file.
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/Mesh.h>

#include <string>

namespace fluidsurf {

/// What becomes of isolated particles (no neighbour within h): the field leaves them out
/// (unless Params::keepIsolated), so without a shape of their own they vanish from the mesh.
enum class IsolatedMode {
    Drop,   ///< left out of the mesh (still listed in ReconstructResult::isolatedParticles)
    Spheres ///< each a closed icosphere of its radius, a component of its own (thesis §5.2.3)
};
const char* isolatedModeName(IsolatedMode m);               ///< "drop", "spheres"
IsolatedMode isolatedModeFromName(const std::string& name); ///< ValueError for unknown names

/// Which decimation runs.
enum class Decimator {
    Quadric, ///< ours: parallel, the same result for any thread count, collapses to the
             ///< point of least error (lib/src/post/Decimate.cc says how)
    OpenMesh ///< OpenMesh's serial Decimater (ModQuadric + ModNormalFlipping), the reference:
             ///< collapses onto an end point; needs a manifold mesh; no error bound
};
const char* decimatorName(Decimator d);               ///< "quadric", "openmesh"
Decimator decimatorFromName(const std::string& name); ///< ValueError for unknown names

/// The volume each closed component is offset back to after the surface steps (at most 0.3
/// voxel; lib/src/post/Volumes.h), which shrink what curves.
enum class VolumeTarget {
    Mesh,     ///< what the raw mesh enclosed
    Particles ///< the particles inside it, sum (2 r_j)^3: SPH's volume of the fluid at rest
              ///< (SSP07's raw surface encloses 80-95% of it on real frames; issue 64)
};
const char* volumeTargetName(VolumeTarget v);               ///< "mesh", "particles"
VolumeTarget volumeTargetFromName(const std::string& name); ///< ValueError for unknown names

/// The particles a mesh was made from, for VolumeTarget::Particles and
/// PostProcessParams::cover (reconstruct() passes its own), world units.
struct ParticleVolumes
{
    const Vec3f* positions = nullptr;
    const float* radii = nullptr; ///< per particle, or null for `radius`
    double radius = 0;
    size_t count = 0;
    /// Particles the surface leaves out on purpose (the field's isolated ones, meshed as
    /// spheres or dropped), ascending indices: not covered.
    const uint32_t* isolated = nullptr;
    size_t isolatedCount = 0;
};

/// Mesh post-processing (thesis chapter 5), in this order: decimation, smoothing (ours), Loop
/// subdivision, the volumes given back, the particle centres left outside covered (ours; with the
/// particles), isolated particles as spheres. Each surface step moves the surface by a bounded
/// amount (a share of half a voxel, lib/src/post/PostProcess.cc), so that thin tips and
/// droplets keep their size.
struct PostProcessParams
{
    /// Decimation (thesis §5.2.1): the fraction of the triangles to remove, cheapest quadric
    /// error first, so flat bumps go before curved detail; [0, 1), 0 for none.
    double decimate = 0.8;
    /// An error bound on decimation, in voxels: no collapse that could leave a vertex more than
    /// decimateError * voxelSize from the input surface (each vertex carries a bound: its
    /// ends' bounds plus its distance to the planes of the triangles it replaces). 0 for none.
    /// With decimate too, decimation stops at whichever comes first. Why not a bound on the
    /// quadric error itself: that is a mean over the merged planes, and on the real frames a
    /// bound of (0.1 voxel)^2 still let thin tips be pulled in by half a voxel.
    double decimateError = 0;
    Decimator decimator = Decimator::Quadric;
    /// The voxel that decimateError and the steps' bounds count in (world units):
    /// reconstruct() sets its own; 0 means the input mesh's mean edge length.
    double voxelSize = 0;
    /// Smoothing after decimation (ours; not in the thesis): rounds of Taubin smoothing along
    /// the normals, each point held within 0.2 voxel of where it was. Quadric decimation keeps
    /// the particles' bumps on flat fluid (it keeps shapes), and one Loop step only halves
    /// them; this takes them out. 0 for none (0 to 100).
    int smooth = 6;
    /// With smooth > 0, the smoothing then flattens flat fluid (ours, issue 64): plain
    /// Laplacian steps where the surface is flat at the scale of several voxels, none where it
    /// curves (droplets, sheets, tips, corners), what they move a region as a whole given back,
    /// each point held within 0.4 voxel. The particles' jitter leaves bumps several voxels wide
    /// on flat water that Taubin's rounds barely touch; with this a jittered slab's top comes
    /// out flatter than splashsurf 0.14's smoothed mesh (BENCHMARKS.md).
    bool flatten = true;
    /// Loop subdivision steps after decimation, each 4x the triangles, rounding off the edges
    /// that decimation leaves (0 to 3).
    int subdivide = 1;
    /// With any step on. Particles where the particles are known (reconstruct(), or
    /// postProcessMesh's `particles`); a mesh alone (`fluidsurf post`, Python's post_process)
    /// keeps its own volumes. On the real frames the particles' volume puts every frame's mesh
    /// closer to N (2r)^3 than splashsurf 0.14's (BENCHMARKS.md, issue 64).
    VolumeTarget volume = VolumeTarget::Particles;
    /// With any step on and the particles known: the chain ends by covering the particle
    /// centres the surface leaves outside (ours, issue 64). SSP07's f-term pulls a thin tip's
    /// surface in past its last particles, by up to 0.7 r on the real frames. Each such centre,
    /// up to a voxel out, gets a smooth bump of the surface around its nearest point (2.5 voxels
    /// wide) that ends with it 0.1 voxel inside; the rest of the surface stays where it was.
    bool cover = true;
    /// reconstruct() only (it has the particles). Spheres by default, as the thesis: a droplet
    /// is part of the fluid, and dropping it silently loses it from the mesh.
    IsolatedMode isolated = IsolatedMode::Spheres;
    /// How far the spheres' faces may dip inside radius r, as a fraction of r: it picks the
    /// icosphere level (0.01: level 3, 1,280 triangles per sphere). (0, 0.5].
    double sphereDeviation = 0.01;
};

/// Throws ValueError naming the first invalid field.
void validate(const PostProcessParams& params);

/// Whether params change a mesh at all (any step on); if not, postProcessMesh returns its input.
bool changesMesh(const PostProcessParams& params);

/// What postProcessMesh did.
struct PostProcessStats
{
    size_t inputTriangles = 0, decimatedTriangles = 0; ///< before and after decimation
    double decimateError = 0; ///< the largest collapse error made, in voxels (its square root)
    /// PostProcessParams::cover: centres the bumps brought inside, and those left outside (over
    /// a voxel out, or a bump would have folded the surface)
    size_t coveredParticles = 0, uncoveredParticles = 0;
};

/// The surface steps of params on mesh, in order, each timed in ctx under the current scope;
/// mesh stays closed, manifold and oriented where it was. particles: those the mesh was made
/// from, for VolumeTarget::Particles (null: the mesh's own volumes). ValueError for invalid
/// params (or a non-manifold mesh for Decimator::OpenMesh), Cancelled when ctx's callback stops
/// it.
TriangleMesh postProcessMesh(TriangleMesh mesh, const PostProcessParams& params, Context& ctx,
                             PostProcessStats* stats = nullptr,
                             const ParticleVolumes* particles = nullptr);

} // namespace fluidsurf
