// ObjInParallel.h - OBJ meshes read on all threads, for the mesh reader (MeshReader.cc), which
// reads a file line by line on one thread where this refuses it, and names what is wrong.
#pragma once

#include <fluidsurf/Mesh.h>

#include <cstddef>
#include <cstdint>

namespace fluidsurf {
namespace io_internal {

/// Lines at least this long are refused (the mesh reader's limit).
constexpr size_t kObjLineLimit = size_t(1) << 20;

/// The mesh of the OBJ text [data, data + size) into `out` (empty), as the mesh reader reads it:
/// v, vn and f with any of the a, a/b, a/b/c, a//c forms, negative indices, polygons cut into
/// triangles (Polygon.h); normals kept when there is one per vertex. False, with `out` in any
/// state, for a file the mesh reader would refuse, or with a line of kObjLineLimit bytes or more.
bool readObjInParallel(const uint8_t* data, size_t size, TriangleMesh& out);

} // namespace io_internal
} // namespace fluidsurf
