// PlaneQuadrics.h - each vertex's quadric (post/Quadric.h) from the planes of its triangles:
// decimation's set-up (Decimate.cc), where it was most of the time before the first pass (the
// three divisions and the root of every corner, one vertex at a time).
#pragma once

#include "post/Normals.h"
#include "post/Quadric.h"

#include <array>
#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace post {

/// Vertex [begin, end)'s quadrics into out[v]: the planes of its triangles (their sides'
/// cross product n, through their first corner, relative to the vertex's point), each
/// weighted by its area |n| / 2, added in the order `around` lists them, then packed
/// (PackedQuadric::pack). A triangle without area adds nothing. `around`: the table of the
/// vertices from `first` (VertexTriangles(triangles, first, last), first <= begin <= end <=
/// last).
/// lanes: 1 (one vertex at a time), 4 (four at a time, one a lane of AVX registers; only where
/// util::doubleRegisterLanes() is 4), or 0 (the default: 4 where it can, else 1); the same bits
/// either way (tests run both). ValueError otherwise.
void planeQuadrics(const Vec3d* points, const std::vector<std::array<uint32_t, 3>>& triangles,
                   const VertexTriangles& around, uint32_t first, uint32_t begin, uint32_t end,
                   PackedQuadric* out, int lanes = 0);

} // namespace post
} // namespace fluidsurf
