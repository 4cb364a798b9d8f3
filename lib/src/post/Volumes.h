// Volumes.h - each closed component's enclosed volume, kept through the surface steps: Loop
// subdivision and smoothing shrink what curves, and a droplet of a voxel or two across loses
// a tenth of its volume or more to moves that are a small fraction of a voxel (measured on
// splashsurf's fluid_250 frame: 11%). The steps' result is offset along its normals, per
// component, back to the volumes their input enclosed.
#pragma once

#include "post/Normals.h"

#include <fluidsurf/Mesh.h>

#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace post {

constexpr uint32_t kNoComponent = UINT32_MAX;

/// The components of a mesh (triangles joined through shared points) and what each encloses.
struct Components
{
    std::vector<uint32_t> ofPoint; ///< each point's component; kNoComponent if no triangle uses it
    std::vector<double> volume;    ///< enclosed volume (divergence theorem; < 0 if inside out)
    std::vector<uint8_t> closed;   ///< every edge of it has exactly two of its triangles
};

/// Components numbered in the order of their lowest point, with their volumes; `closed` is
/// left empty (see markClosed).
Components findComponents(const TriangleMesh& mesh);

/// c.closed from mesh, whose points' components are `ofPoint` (another mesh than the one c
/// was found on, as long as the steps between keep borders: decimation does, and the check
/// counts every side, cheaper on the decimated mesh).
void markClosed(Components& c, const TriangleMesh& mesh, const std::vector<uint32_t>& ofPoint);

/// For a mesh made from one whose components are `before` (`ofPoint`: each point's component,
/// kNoComponent for points the steps added, which get the component of a triangle neighbour):
/// moves the points of each component that is closed in `before` along their normals by the
/// one offset that gives back its old volume (to first order), at most maxOffset (world units).
/// around: mesh's vertex -> triangle table. Leaves mesh.normals as scratch: the chain's end
/// computes them (see Normals.h).
void restoreVolumes(TriangleMesh& mesh, std::vector<uint32_t> ofPoint, const Components& before,
                    double maxOffset, const VertexTriangles& around);

} // namespace post
} // namespace fluidsurf
