// LoopSubdivision.h - Loop subdivision (Loop 1987; thesis §5.2.2): after decimation has made a
// mesh coarse and its edges sharp, one step rounds them off again at four times the triangles.
#pragma once

#include <fluidsurf/Mesh.h>

#include <limits>

namespace fluidsurf {
namespace post {

/// One Loop step: every triangle cut into four (orientation kept); a new point on each edge at
/// 3/8 of its two ends and 1/8 of the two opposite corners; each old point moved towards its n
/// neighbours with Loop's weight beta(n). Edges of one triangle (a boundary) or of three or more
/// (non-manifold) are creases: their new points are midpoints and their points follow the cubic
/// B-spline along them, corners rounded like the rest (a point on other than two creases stays).
/// Old points keep their indices, edge points follow in edge order; no normals (Normals.h).
/// The same bits for any thread count.
///
/// maxMove (world units) bounds how far a point moves from where it is, or an edge point from
/// its edge's middle: Loop's limit surface lies inside a convex mesh, and on a tip of a voxel's
/// radius the plain rules pull the point in by more than half a voxel (measured on the real
/// frames); on flat fluid the moves are far below any useful bound, so the rounding off stays.
TriangleMesh loopSubdivide(const TriangleMesh& mesh,
                           double maxMove = std::numeric_limits<double>::infinity());

} // namespace post
} // namespace fluidsurf
