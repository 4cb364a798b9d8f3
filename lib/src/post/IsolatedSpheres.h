// IsolatedSpheres.h - isolated particles as pre-tessellated spheres (thesis §5.2.3): a particle
// with no neighbour within h has no surface of its own in the field, so it becomes a closed
// icosphere of its radius, appended to the mesh as a component of its own.
#pragma once

#include <fluidsurf/Mesh.h>

#include <vector>

namespace fluidsurf {
namespace post {

/// The unit icosphere of a subdivision level: the icosahedron with each triangle split in four
/// `level` times and every vertex on the unit sphere; 10 * 4^level + 2 vertices, 20 * 4^level
/// triangles, closed, manifold, counter-clockwise seen from outside, normals radial.
TriangleMesh unitIcosphere(int level);

/// How far a unit icosphere's faces dip inside the unit sphere: 1 - the smallest distance of a
/// face's plane from the centre (its vertices lie on the sphere; the faces do not).
double icosphereDeviation(const TriangleMesh& unitSphere);

/// The coarsest level whose faces stay within maxDeviation (a fraction of the radius) of the
/// sphere; 1% gives level 3 (1,280 triangles).
int icosphereLevelFor(double maxDeviation);

/// Appends one sphere per centre: radius radii[i], or radii[0] for all when it holds one value.
/// Normals are added when mesh has normals or is empty. Deterministic for any thread count.
void appendSpheres(TriangleMesh& mesh, const std::vector<Vec3f>& centres,
                   const std::vector<float>& radii, int level);

} // namespace post
} // namespace fluidsurf
