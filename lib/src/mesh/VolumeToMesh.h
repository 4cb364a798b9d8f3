// VolumeToMesh.h - OpenVDB's tools::volumeToMesh as a mesher (--mesher openvdb): adaptivity 0,
// quads split into two triangles, normals from the field gradient like our own mesher.
#pragma once

#include <fluidsurf/MeshLevelSet.h>

namespace fluidsurf {
namespace mesh {

TriangleMesh openvdbVolumeToMesh(const openvdb::FloatGrid& grid);

} // namespace mesh
} // namespace fluidsurf
