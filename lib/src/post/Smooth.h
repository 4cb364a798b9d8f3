// Smooth.h - bounded smoothing along the normals, between decimation and subdivision: the
// particles' bumps on flat fluid survive quadric decimation (its placement keeps a bump's shape,
// which is what it is for), and one Loop step only halves them; this removes them while no
// point moves farther than a bound, so thin tips and droplets keep their size.
#pragma once

#include <fluidsurf/Mesh.h>

#include "post/Normals.h"

#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace post {

/// What smoothAlongNormals does; lengths in world units.
struct SmoothParams
{
    /// Rounds of Taubin's lambda|mu smoothing (1995) with lambda = 0.5, mu = -0.5, each step
    /// moving a point along its normal by that fraction of its offset from its neighbours'
    /// mean; every point stays within maxMove of where it started.
    int rounds = 0;
    double maxMove = 0;
    /// Then flatten the flat regions (ours, issue 64). Taubin's pair barely touches bumps
    /// several voxels wide (its transfer is 1 - k^2/4 for a Laplacian eigenvalue k), and those
    /// are what is left of the particles' jitter on flat fluid. So: plain Laplacian steps along
    /// the normals towards the mean of a point's flat neighbours, at full weight where the surface
    /// is flat at the scale of several voxels (its curvature, taken on a copy that plain Laplacian
    /// steps have smoothed, below 1/(33 voxels) over two rings), none where it passes 1/(12.5
    /// voxels), linear between. Plain Laplacian steps also shrink a curved body as a whole; that
    /// slow part of what they moved is given back, so that the bumps go and the body stays. A flat
    /// point stays within flatMove of where it started, a point of weight w within maxMove +
    /// (flatMove - maxMove) w^2. voxel: the unit of the curvatures.
    bool flatten = false;
    double flatMove = 0;
    double voxel = 0;
};

/// params' steps on mesh. Points on an open border, on a non-manifold edge or unused do not
/// move. Topology unchanged; no normals (Normals.h says why). The same bits for any thread
/// count. mesh by value: its arrays become the result's (move a mesh in to spare the copy).
TriangleMesh smoothAlongNormals(TriangleMesh mesh, const SmoothParams& params);

/// What smoothAlongNormals walks, as plain arrays for the GPU's smoothing (backend/): each
/// point's triangles (corners), its neighbours ascending, ring[ringStart[v], ringStart[v + 1]),
/// and fixed[v]: on an open border or a non-manifold edge, where it stays.
struct SmoothRings
{
    VertexTriangles corners;
    std::vector<uint32_t> ringStart, ring;
    std::vector<uint8_t> fixed;
};
SmoothRings smoothRings(const TriangleMesh& mesh);

/// Whether params leave mesh as it is (smoothAlongNormals returns it unchanged, normals and all).
bool smoothingLeaves(const TriangleMesh& mesh, const SmoothParams& params);

/// Taubin rounds only (SmoothParams' first two fields).
TriangleMesh smoothAlongNormals(TriangleMesh mesh, int iterations, double maxMove);

} // namespace post
} // namespace fluidsurf
