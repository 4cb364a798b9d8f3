// Mesh.h - an indexed triangle mesh: each vertex stored once, triangles counter-clockwise seen
// from outside, one normal per vertex (optional: empty when not computed).
#pragma once

#include <fluidsurf/Vec3.h>

#include <array>
#include <cstdint>
#include <vector>

namespace fluidsurf {

struct TriangleMesh
{
    std::vector<Vec3f> points;
    std::vector<Vec3f> normals; ///< empty, or one per point
    std::vector<std::array<uint32_t, 3>> triangles;

    bool empty() const { return triangles.empty(); }
};

/// A mesher's vertex normals: from the field's gradient, or none (mesh.normals empty) for a mesh
/// that post-processing will change anyway: it computes its own, and the gradients and 12 bytes
/// a vertex are saved.
enum class RawNormals { Gradient, None };

} // namespace fluidsurf
