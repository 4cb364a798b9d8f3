// Smooth.h - the post-processing smoothing on the GPU (host facade, no CUDA syntax): the CPU's
// steps (lib/src/post/Smooth.h: Taubin's pairs along the normals, then the flat regions
// flattened) on the same arrays, in the same order, with the same arithmetic (no FMA
// contraction; the numbers of lib/src/post/SmoothSteps.h), so that the points come out bit for
// bit as the CPU's. One thread a point or a triangle; every per-point sum runs over the point's
// own list in the CPU's order.
//
// In: the mesh's points and triangles, each point's triangles (corner table) and its ring of
// neighbours ascending (post::smoothRings), which the host builds; out: the smoothed points.
#pragma once

#include <fluidsurf/Vec3.h>

#include <cstddef>
#include <cstdint>
#include <functional>

namespace fluidsurf {
namespace cuda {

/// The cell grid of the thin test's cell index for points in [lo, hi] and cells of cellSize:
/// origin and dims, by the CPU's arithmetic (neighbors::cellGrid), which the host supplies.
using CellGridRule = std::function<void(const float lo[3], const float hi[3], double cellSize,
                                        double origin[3], uint32_t dims[3])>;

struct SmoothInput
{
    const Vec3f* points = nullptr;
    size_t pointCount = 0;
    const uint32_t* triangles = nullptr; ///< 3 a triangle
    size_t triangleCount = 0;
    const uint32_t* cornerStart = nullptr; ///< pointCount + 1
    const uint32_t* cornerTris = nullptr;  ///< 3 * triangleCount: each point's triangles
    const uint32_t* ringStart = nullptr;   ///< pointCount + 1
    const uint32_t* ring = nullptr;        ///< each point's neighbours, ascending
    const uint8_t* fixed = nullptr;        ///< pointCount: stays (border, non-manifold)
    /// post::SmoothParams: Taubin rounds and the bound of each point's move (world units);
    /// flatten, its bound and the voxel its curvatures count in
    int rounds = 0;
    double maxMove = 0;
    bool flatten = false;
    double flatMove = 0, voxel = 0;
    CellGridRule cellGrid;
};

/// The smoothed points into out (pointCount). Throws fluidsurf::Error on CUDA errors.
void smoothPoints(const SmoothInput& input, Vec3f* out, void* stream = nullptr);

} // namespace cuda
} // namespace fluidsurf
