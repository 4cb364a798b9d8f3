// OpenVdbBaselines.h - OpenVDB's own particle rasterizers at the same voxel size, for the field
// benchmark: tools::ParticlesToLevelSet (sphere stamping) and points::rasterizeSmoothSpheres
// (Zhu-Bridson averaged positions). Own translation unit: PointRasterizeSDF.h is heavy.
#pragma once

#include <fluidsurf/ParticleSet.h>

#include <cstddef>

namespace fluidsurf {
namespace bench {

struct BaselineResult
{
    double seconds = 0;      ///< the rasterization itself
    double setupSeconds = 0; ///< building the PointDataGrid (smooth spheres only)
    size_t activeVoxels = 0;
};

BaselineResult runParticlesToLevelSet(const ParticleSet& ps, double radius, double voxel);
BaselineResult runSmoothSpheres(const ParticleSet& ps, double radius, double searchRadius,
                                double voxel);

} // namespace bench
} // namespace fluidsurf
