// MeshLevelSet.h - level set -> indexed triangle mesh (thesis §4.2.2, "Triangulation").
//
// meshLevelSet triangulates the zero crossing of a FloatGrid level set (ours, or any VDB tool's)
// with one of two meshers:
// - MarchingCubes (default): our marching cubes over the active narrow band. Only cells whose
//   eight corners are active are triangulated (no double layers); each edge crossing becomes one
//   shared vertex; ambiguous faces are resolved by the bilinear saddle value, which both cells of
//   a face compute from the same four values, so the mesh is closed and manifold wherever the
//   band encloses the surface. Parallel over VDB leaves (TBB), identical output for any thread
//   count. Vertex normals come from the field gradient (central differences). With the context's
//   device cuda (or auto and a usable GPU) it runs on the GPU, with the same bytes.
// - OpenVdb: OpenVDB's tools::volumeToMesh (adaptivity 0), quads split into triangles, normals
//   from the same gradient, for comparison and for users who want OpenVDB's dual surface.
// Triangles are counter-clockwise seen from outside (where phi > 0).
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/Mesh.h>

#include <openvdb/openvdb.h>

#include <cstddef>
#include <string>

namespace fluidsurf {

enum class Mesher { MarchingCubes, OpenVdb };

const char* mesherName(Mesher m);               ///< "mc" or "openvdb"
Mesher mesherFromName(const std::string& name); ///< ValueError for an unknown name

struct MeshStats
{
    size_t surfaceCells = 0; ///< cells with a sign change (MarchingCubes only)
    size_t vertices = 0, triangles = 0;
    /// where it ran: "cpu", the GPU's name, or "cpu (...)" saying why not on the GPU asked for
    std::string device;
};

/// Triangulate the zero level of grid (timed in ctx.timing() as "mesh"; the grid's own transform
/// is the level) on ctx.device() (MarchingCubes; OpenVdb runs on the CPU). ValueError when the
/// grid is not a level set-like FloatGrid (no active voxels is fine: the mesh is empty); Error
/// for device cuda without a usable GPU; Cancelled when ctx's callback stopped it.
TriangleMesh meshLevelSet(const openvdb::FloatGrid& grid, Mesher mesher, Context& ctx,
                          MeshStats* stats = nullptr, RawNormals normals = RawNormals::Gradient);

/// The same with a context of its own: CPU, all cores, no callback.
TriangleMesh meshLevelSet(const openvdb::FloatGrid& grid, Mesher mesher = Mesher::MarchingCubes,
                          MeshStats* stats = nullptr);

} // namespace fluidsurf
