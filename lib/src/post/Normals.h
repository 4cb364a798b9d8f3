// Normals.h - vertex normals of a mesh from its faces, for meshes whose vertices no longer sit
// on the field (after decimation or subdivision; spheres). The raw marching-cubes mesh keeps the
// field-gradient normals it is made with.
#pragma once

#include <fluidsurf/Mesh.h>

namespace fluidsurf {
namespace post {

/// mesh.normals from the triangles around each vertex, each weighted by its angle at the vertex
/// (Thürmer and Wüthrich 1998): unlike area weights, this does not depend on how a flat region
/// happens to be cut into triangles. Unit length; zero for a vertex no triangle uses or whose
/// triangles cancel. Sums in triangle order per vertex: the same bits for any thread count.
void computeAngleWeightedNormals(TriangleMesh& mesh);

} // namespace post
} // namespace fluidsurf
