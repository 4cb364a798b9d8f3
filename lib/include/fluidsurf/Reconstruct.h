// Reconstruct.h - the whole reconstruction as one call (DESIGN.md, "Pipeline and layout"):
//
//   particles -> radius choice -> rasterizeParticles (neighbors, classify, narrow band, field,
//   level set) -> meshLevelSet (marching cubes) -> post-processing (ch. 5: decimation,
//   smoothing, Loop subdivision, isolated particles as spheres) -> particle attributes at the
//   vertices (TransferAttributes.h) -> result
//
// With field.adaptive, rasterizeParticles builds the 3-level grid of ch. 6 and
// meshAdaptiveGrid (AdaptiveGrid.h) meshes it instead of meshLevelSet.
//
// Front ends (the CLI, the benchmark, later Python) are thin layers over this header; the two
// halves, rasterizeParticles (Rasterize.h) and meshLevelSet (MeshLevelSet.h), stay public.
//
//   fluidsurf::ReconstructParams params = fluidsurf::ReconstructParams::fromRadius(0.025);
//   fluidsurf::Context ctx;                       // CPU, all cores; ctx.setDevice(Device::Auto)
//   fluidsurf::ReconstructResult res = fluidsurf::reconstruct(particles, params, ctx);
//   res.levelSet (FloatGrid "surface"), res.mesh, res.isolatedParticles, ctx.timing().format()
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/Mesh.h>
#include <fluidsurf/MeshLevelSet.h>
#include <fluidsurf/Params.h>
#include <fluidsurf/ParticleSet.h>
#include <fluidsurf/PostProcess.h>
#include <fluidsurf/Rasterize.h>

#include <openvdb/openvdb.h>

#include <string>
#include <vector>

namespace fluidsurf {

/// The meshing section.
struct MeshParams
{
    Mesher mesher = Mesher::MarchingCubes;
};

struct ReconstructParams
{
    /// r, world units: the particle radius (half the rest spacing). 0: chosen from the frame by
    /// chooseRadius (the radius attribute, else an estimate; the result says which).
    double radius = 0;
    /// The field, with every length in units of r (Params::fromRadius(1): voxel 1 means dx = r,
    /// influenceRadius 4 means R = 4r); field.radius is ignored (see radius above).
    Params field = Params::fromRadius(1);
    MeshParams mesh;
    PostProcessParams post;
    /// Particle attributes to carry onto the mesh's vertices (TransferAttributes.h: "v",
    /// "density", "id", or an alias such as "velocity"), into ReconstructResult::vertexAttributes.
    std::vector<std::string> attributes;
    /// Keep the level set in ReconstructResult. false frees it once the mesh is made, before
    /// post-processing: a run that writes only the mesh then peaks lower by the band's size
    /// (about 130 MB on a 1.7M-particle frame). The adaptive grid (field.adaptive) is kept.
    bool keepGrids = true;

    /// The DESIGN.md defaults for particle radius r.
    static ReconstructParams fromRadius(double r);
    /// The field parameters in world units for radius r.
    Params fieldParams(double r) const;
};

enum class RadiusSource {
    Given,     ///< ReconstructParams::radius
    Attribute, ///< the largest value of the radius attribute (pscale)
    Estimated  ///< half the spacing estimateSpacing finds (SpacingEstimate.h): an estimate, say so
};
const char* radiusSourceName(RadiusSource s); ///< "given", "attribute", "estimate"

struct RadiusChoice
{
    double radius = 0;
    RadiusSource source = RadiusSource::Given;
    std::string detail; ///< e.g. "largest value of the attribute 'pscale'"
};

/// r for these particles: given (> 0), else the radius attribute's largest value (when
/// useAttribute), else an estimate. ValueError when none can be had (fewer than two particles).
/// The estimate runs on ctx's threads and is timed there as "radius estimate" (a tenth of a
/// 1.7M-particle frame's reconstruction).
RadiusChoice chooseRadius(const ParticleSet& particles, double given, bool useAttribute,
                          Context& ctx);
/// The same under a default Context.
RadiusChoice chooseRadius(const ParticleSet& particles, double given, bool useAttribute = true);

struct ReconstructResult
{
    /// The "surface" level set (Rasterize.h); null without ReconstructParams::keepGrids (on the
    /// uniform grid).
    openvdb::FloatGrid::Ptr levelSet;
    /// With field.adaptive: the three grids of the 3-level grid (levelSet is its level 2), and
    /// what the adaptive mesher made (AdaptiveGrid.h).
    AdaptiveGrid adaptiveGrid;
    AdaptiveMeshStats adaptiveMesh;
    TriangleMesh mesh;
    /// ReconstructParams::attributes at mesh's vertices, in that order (one value per vertex).
    std::vector<Attribute> vertexAttributes;
    std::vector<uint32_t> isolatedParticles; ///< input indices left out of the surface
    /// Of them, appended to mesh as spheres (IsolatedMode::Spheres): all but those too far from
    /// the origin for float32 to place a sphere's vertices (beyond ~8,000 radii).
    size_t isolatedSpheres = 0;
    RadiusChoice radius;
    RasterizeStats field;
    MeshStats meshing;
    PostProcessStats post;
};

/// The whole reconstruction of one frame. sourceName goes into the level set's metadata.
/// ValueError for invalid parameters or input, Cancelled when ctx's callback stopped it.
ReconstructResult reconstruct(const ParticleSet& particles, const ReconstructParams& params,
                              Context& ctx, const std::string& sourceName = "");

} // namespace fluidsurf
