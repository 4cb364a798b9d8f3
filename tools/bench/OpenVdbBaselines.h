// OpenVdbBaselines.h - OpenVDB's own particle rasterizers at the same voxel size, for the field
// benchmark: tools::ParticlesToLevelSet (sphere stamping) and points::rasterizeSmoothSpheres
// (Zhu-Bridson averaged positions). Own translation unit: PointRasterizeSDF.h is heavy.
#pragma once

#include <fluidsurf/Mesh.h>
#include <fluidsurf/ParticleSet.h>

#include <openvdb/openvdb.h>

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

/// OpenVDB's tools::volumeToMesh of grid with the given adaptivity (0..1), quads split into
/// triangles, no normals: the adaptive baseline of the adaptive-grid benchmark.
TriangleMesh openvdbAdaptiveMesh(const openvdb::FloatGrid& grid, double adaptivity);

} // namespace bench
} // namespace fluidsurf
