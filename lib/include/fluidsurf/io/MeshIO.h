// MeshIO.h - write triangle meshes (and read OBJ and PLY back): Wavefront OBJ (v, vn, f v//vn),
// binary little-endian PLY (x y z [nx ny nz] + vertex_indices), legacy VTK POLYDATA (binary).
// Chosen by extension; written atomically.
#pragma once

#include <fluidsurf/Mesh.h>

#include <cstddef>
#include <cstdint>
#include <string>

namespace fluidsurf {
namespace io {

enum class MeshFormat { Unknown, Obj, Ply, Vtk };

MeshFormat meshFormatFromPath(const std::string& path);

/// OutputError for an unknown extension, indices out of range or a failed write.
void writeMesh(const TriangleMesh& mesh, const std::string& path);

/// Read an OBJ or PLY mesh (polygons fanned into triangles; normals kept when there is one per
/// vertex). InputError naming the file, the problem and where (line or byte).
TriangleMesh readMesh(const std::string& path);

/// The same from bytes in memory (format Obj or Ply); source names them in errors.
TriangleMesh readMeshFromMemory(const uint8_t* data, size_t size, MeshFormat format,
                                const std::string& source);

} // namespace io
} // namespace fluidsurf
