// Normals.h - vertex normals of a mesh from its faces, for meshes whose vertices no longer sit
// on the field (after decimation or subdivision; spheres). The raw marching-cubes mesh keeps the
// field-gradient normals it is made with.
#pragma once

#include <fluidsurf/Mesh.h>

#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace post {

/// Each vertex's triangles, in triangle order (a table built by counting): what per-vertex sums
/// over triangles gather from, in the same order on every run.
struct VertexTriangles
{
    std::vector<uint32_t> start; ///< vertex v's triangles are tris[start[v], start[v + 1])
    std::vector<uint32_t> tris;
    explicit VertexTriangles(const TriangleMesh& mesh);
};

/// mesh.normals from the triangles around each vertex, each weighted by its angle at the vertex
/// (Thürmer and Wüthrich 1998): unlike area weights, this does not depend on how a flat region
/// happens to be cut into triangles. Unit length; zero for a vertex no triangle uses or whose
/// triangles cancel. Sums in triangle order per vertex: the same bits for any thread count.
void computeAngleWeightedNormals(TriangleMesh& mesh);

} // namespace post
} // namespace fluidsurf
