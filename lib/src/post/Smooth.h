// Smooth.h - bounded smoothing along the normals, between decimation and subdivision: the
// particles' bumps on flat fluid survive quadric decimation (its placement keeps a bump's shape,
// which is what it is for), and one Loop step only halves them; this removes them while no
// point moves farther than a bound, so thin tips and droplets keep their size.
#pragma once

#include <fluidsurf/Mesh.h>

namespace fluidsurf {
namespace post {

/// `iterations` rounds of Taubin's lambda|mu smoothing (1995) with lambda = 0.5, mu = -0.5,
/// each step moving a point along its normal by that fraction of its offset from its
/// neighbours' mean; every point stays within maxMove (world units) of where it started.
/// Points on an open border, on a non-manifold edge or unused do not move. Topology unchanged;
/// no normals (Normals.h says why). The same bits for any thread count. mesh by value: its
/// arrays become the result's (move a mesh in to spare the copy).
TriangleMesh smoothAlongNormals(TriangleMesh mesh, int iterations, double maxMove);

} // namespace post
} // namespace fluidsurf
