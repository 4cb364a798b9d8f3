// VolumeToMesh.h - OpenVDB's tools::volumeToMesh as a mesher (--mesher openvdb): adaptivity 0,
// quads split into two triangles, normals from the field gradient like our own mesher.
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/Mesh.h>

#include <openvdb/openvdb.h>

namespace fluidsurf {
namespace mesh {

/// volumeToMesh itself has no interrupter: ctx.checkpoint() runs only in the normals pass.
TriangleMesh openvdbVolumeToMesh(const openvdb::FloatGrid& grid, Context& ctx);

} // namespace mesh
} // namespace fluidsurf
