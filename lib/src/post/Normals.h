// Normals.h - vertex normals of a mesh from its faces, for meshes whose vertices no longer sit
// on the field (after decimation or subdivision; spheres). The raw marching-cubes mesh keeps the
// field-gradient normals it is made with. The surface steps (decimation, smoothing, Loop) leave
// a mesh without normals: none of them reads the last one's, so postProcessMesh computes them
// once, at the end of the chain (on the 1.7M-particle frame, five passes of atan2 were a tenth
// of the post-processing).
#pragma once

#include <fluidsurf/Mesh.h>

#include "util/Memory.h"
#include "util/Vec3d.h"

#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace post {

/// Each vertex's triangles, in triangle order (a table built by counting): what per-vertex sums
/// over triangles gather from, in the same order on every run.
struct VertexTriangles
{
    /// vertex v's triangles are tris[start[v], start[v + 1]) (not zeroed first: filled whole)
    util::NoInitVector<uint32_t> start, tris;
    explicit VertexTriangles(const TriangleMesh& mesh);
    /// The same for `points` vertices (a mesh whose points live elsewhere).
    VertexTriangles(const std::vector<std::array<uint32_t, 3>>& triangles, size_t points);
    /// The same for vertices [first, last) only, indexed from first: vertex v's triangles are
    /// tris[start[v - first], start[v - first + 1]) (a table made in parts, to keep it small).
    VertexTriangles(const std::vector<std::array<uint32_t, 3>>& triangles, uint32_t first,
                    uint32_t last);
};

/// mesh.normals from the triangles around each vertex, each weighted by its angle at the vertex
/// (Thürmer and Wüthrich 1998): unlike area weights, this does not depend on how a flat region
/// happens to be cut into triangles. Unit length; zero for a vertex no triangle uses or whose
/// triangles cancel. Sums in triangle order per vertex: the same bits for any thread count.
void computeAngleWeightedNormals(TriangleMesh& mesh);
/// The same with mesh's vertex -> triangle table at hand.
void computeAngleWeightedNormals(TriangleMesh& mesh, const VertexTriangles& around);

/// Triangle t's side cross product (b - a) x (c - a) at points p (Vec3f or Vec3d, indexed by
/// point): its normal, twice its area long.
template <typename Points> Vec3d sideCross(const Points& p, const std::array<uint32_t, 3>& t)
{
    const Vec3d a = toVec3dAny(p[t[0]]);
    return (toVec3dAny(p[t[1]]) - a).cross(toVec3dAny(p[t[2]]) - a);
}

/// Point v's area-weighted normal at points p, not normalised: the sum of its triangles' side
/// cross products (each computed here: no buffer the size of the mesh).
template <typename Points>
Vec3d areaNormal(const Points& p, const TriangleMesh& mesh, const VertexTriangles& around, size_t v)
{
    Vec3d n(0.0);
    for (uint32_t i = around.start[v]; i < around.start[v + 1]; ++i)
        n += sideCross(p, mesh.triangles[around.tris[i]]);
    return n;
}

/// Area-weighted vertex normals at points of one's own (the mesh's triangles, other positions):
/// each vertex's sum of its triangles' side cross products, not normalised. Cheap (no angles:
/// each triangle's cross product once), for steps that need only a direction. Keeps its buffers
/// between calls. The same bits for any thread count.
class AreaNormals
{
public:
    AreaNormals(const TriangleMesh& mesh, const VertexTriangles& around)
        : mMesh(mesh), mAround(around)
    {
    }
    /// normals()[v] for points p (one per mesh point)
    void compute(const Vec3d* p);
    const util::NoInitVector<Vec3d>& normals() const { return mNormals; }

private:
    const TriangleMesh& mMesh;
    const VertexTriangles& mAround;
    util::NoInitVector<Vec3d> mCross, mNormals; ///< (each written whole by compute)
};

} // namespace post
} // namespace fluidsurf
