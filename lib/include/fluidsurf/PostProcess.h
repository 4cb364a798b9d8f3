// PostProcess.h - mesh post-processing (thesis chapter 5) on any closed triangle mesh: today Loop
// subdivision (decimation to come), with angle-weighted normals after each step. reconstruct()
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

/// Mesh post-processing (thesis chapter 5), in this order: (decimation: to come), Loop
/// subdivision, isolated particles as spheres.
struct PostProcessParams
{
    /// Loop subdivision steps, each 4x the triangles, normals then angle-weighted (0 to 3). The
    /// thesis runs one after decimation; until decimation is here the default is none, since
    /// on the raw mesh it only multiplies the triangles.
    int subdivide = 0;
    /// reconstruct() only (it has the particles). Spheres by default, as the thesis: a droplet
    /// is part of the fluid, and dropping it silently loses it from the mesh.
    IsolatedMode isolated = IsolatedMode::Spheres;
    /// How far the spheres' faces may dip inside radius r, as a fraction of r: it picks the
    /// icosphere level (0.01: level 3, 1,280 triangles per sphere). (0, 0.5].
    double sphereDeviation = 0.01;
};

/// Throws ValueError naming the first invalid field.
void validate(const PostProcessParams& params);

/// The surface steps of params on mesh, in order, each timed in ctx under the current scope;
/// mesh stays closed, manifold and oriented where it was. ValueError for invalid params,
/// Cancelled when ctx's callback stops it.
TriangleMesh postProcessMesh(TriangleMesh mesh, const PostProcessParams& params, Context& ctx);

} // namespace fluidsurf
