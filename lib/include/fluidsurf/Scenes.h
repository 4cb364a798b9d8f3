// Scenes.h - deterministic particle scenes with known surfaces, for tests, benchmarks and the
// demo. Particles sit on a cubic lattice of spacing 2r (r = particle radius); the same
// parameters give the same particles, bit for bit, on every machine.
//
//   single  one particle at the origin (surface: sphere of radius r)
//   block   n x n x n lattice cube, corner at the origin (n = round(cbrt(count)))
//   ball    lattice points within rho spacings of the origin (rho from count)
//   slab    a flat lattice slab `layers` particles thick, jittered in-plane by `jitter` spacings
//   drop    a ball falling into a pool (W x W x W/poolAspect, times poolDepthScale in depth,
//           at least 3 layers) plus a few isolated droplets
//   sheet   a quarter of a cylinder's wall (bent about the y axis, inner radius 8 spacings or
//           more), `layers` particles thick (1 or 2 for the thin sheets of issue 64), jittered
//           in all three directions by `jitter` spacings
//   jet     a thin parabolic jet (a fountain's arc in the x-z plane), `layers` x `layers`
//           particles across, slices one spacing apart along the arc, jittered by `jitter`
#pragma once

#include <fluidsurf/ParticleSet.h>

#include <cstdint>
#include <string>
#include <vector>

namespace fluidsurf {

enum class Scene { Single, Block, Ball, Slab, Drop, Sheet, Jet };

struct SceneParams
{
    double radius = 0.025; ///< particle radius r, world units
    size_t count = 10000;  ///< approximate particle count
    uint64_t seed = 1;     ///< jitter / droplet placement seed
    double jitter = 0.05;  ///< slab: in-plane jitter amplitude; sheet, jet: in 3D; in spacings
    int layers = 4;        ///< slab, sheet: thickness in particles; jet: particles across
    double poolDepthScale = 1.0; ///< drop: pool depth multiplier (more interior)
    double poolAspect = 4.0;     ///< drop: pool width / depth (48: side walls ~4% of the surface)
    int droplets = 5;            ///< drop: isolated single particles
};

Scene sceneFromName(const std::string& name); ///< ValueError for an unknown name
const char* sceneName(Scene scene);
std::vector<std::string> sceneNames();

/// Particles with an int "id" attribute (0..N-1). ValueError for invalid parameters.
ParticleSet generateScene(Scene scene, const SceneParams& params);

} // namespace fluidsurf
