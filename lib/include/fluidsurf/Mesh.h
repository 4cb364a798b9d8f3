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

} // namespace fluidsurf
