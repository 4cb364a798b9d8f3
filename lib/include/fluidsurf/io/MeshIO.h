// MeshIO.h - write triangle meshes (and read OBJ and PLY back): Wavefront OBJ (v, vn, f v//vn),
// binary little-endian PLY (x y z [nx ny nz] + vertex_indices), legacy VTK POLYDATA (binary).
// Chosen by extension; written atomically.
#pragma once

#include <fluidsurf/Mesh.h>
#include <fluidsurf/ParticleSet.h>

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace fluidsurf {
namespace io {

enum class MeshFormat { Unknown, Obj, Ply, Vtk };

MeshFormat meshFormatFromPath(const std::string& path);

/// OutputError for an unknown extension, indices out of range or a failed write.
void writeMesh(const TriangleMesh& mesh, const std::string& path);
/// The same with per-vertex attributes (e.g. ReconstructResult::vertexAttributes): PLY vertex
/// properties after the normals (a 3-vector "v" as vx vy vz, other vectors v0 v1 ..., integers
/// as int), VTK point-data field arrays. OutputError for OBJ (it cannot hold them), a size that
/// does not match the vertices, or an integer beyond 32 bits.
void writeMesh(const TriangleMesh& mesh, const std::string& path,
               const std::vector<Attribute>& vertexAttributes);

/// Read an OBJ or PLY mesh (polygons fanned into triangles; normals kept when there is one per
/// vertex). InputError naming the file, the problem and where (line or byte).
/// droppedProperties (when given) receives the names of PLY vertex properties beyond x y z and
/// nx ny nz, which a TriangleMesh does not hold (e.g. the vx vy vz of writeMesh's attributes).
TriangleMesh readMesh(const std::string& path,
                      std::vector<std::string>* droppedProperties = nullptr);

/// The same from bytes in memory (format Obj or Ply); source names them in errors.
TriangleMesh readMeshFromMemory(const uint8_t* data, size_t size, MeshFormat format,
                                const std::string& source,
                                std::vector<std::string>* droppedProperties = nullptr);

} // namespace io
} // namespace fluidsurf
