// CoverParticles.h - the chain's last move (ours, issue 64): the particle centres that the
// surface leaves outside are covered. SSP07's f-term pulls a thin tip's surface in past its last
// particles (it shrinks r-bar where x-bar moves fast, and at a tip it does), and the surface
// steps' bounded moves do not give that back: on the double dam break, 16 of 4,731 centres lay
// outside the default mesh, up to 0.5 r from it (19 outside the raw mesh). A bump of the surface
// around each brings it inside; the rest of the surface does not move.
#pragma once

#include "post/Normals.h"

#include <fluidsurf/Mesh.h>

#include <vector>

namespace fluidsurf {
namespace post {

/// Lengths in world units.
struct CoverParams
{
    double margin = 0;   ///< how far inside a covered centre ends (at least half of it)
    double reach = 0;    ///< the bump's radius around the surface point nearest the centre
    double maxDepth = 0; ///< centres farther outside are left alone: not this surface's to cover
};

/// What coverParticles did.
struct CoverStats
{
    size_t covered = 0; ///< centres a bump brought inside
    size_t left = 0;    ///< centres too far out, or whose bump would have folded a triangle
};

/// Covers each of `centres` that lies outside mesh, or inside by less than half the margin, and
/// at most maxDepth out. Inside or out is the sign along the normal at the nearest surface point
/// q (the corners' normals, by its barycentric weights: right at corners and sides too). The
/// points of the surface sheet around q (connected to q's triangle within reach of the centre),
/// within reach of q and facing the centre, move along q -> centre by the centre's depth plus the
/// margin, times (1 - (d / reach)^2)^2 for their distance d from q: a smooth bump whose top
/// passes the centre. Again from the new nearest point until the centre is inside (six bumps
/// at most); a bump that turns a triangle by more than 60 degrees, or does not get there, is
/// taken back. Which centres need a bump is found on the mesh as it comes, all at once; the
/// bumps then go in the centres' order where their surroundings share a triangle, at once where
/// not: the same bits for any thread count. around: mesh's vertex -> triangle table. Moves
/// points only; leaves the normals as they were.
CoverStats coverParticles(TriangleMesh& mesh, const VertexTriangles& around,
                          const std::vector<Vec3f>& centres, const CoverParams& params);

} // namespace post
} // namespace fluidsurf
