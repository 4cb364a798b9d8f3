// MeshLevelSet.h - level set -> indexed triangle mesh (thesis §4.2.2, "Triangulation").
//
// meshLevelSet triangulates the zero crossing of a FloatGrid level set (ours, or any VDB tool's)
// with one of two meshers:
// - MarchingCubes (default): our marching cubes over the active narrow band. Only cells whose
//   eight corners are active are triangulated (no double layers); each edge crossing becomes one
//   shared vertex; ambiguous faces are resolved by the bilinear saddle value, which both cells of
//   a face compute from the same four values, so the mesh is closed and manifold wherever the
//   band encloses the surface. Parallel over VDB leaves (TBB), identical output for any thread
//   count. Vertex normals come from the field gradient (central differences).
// - OpenVdb: OpenVDB's tools::volumeToMesh (adaptivity 0), quads split into triangles, normals
//   from the same gradient, for comparison and for users who want OpenVDB's dual surface.
// Triangles are counter-clockwise seen from outside (where phi > 0).
#pragma once

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
    double seconds = 0;
};

/// Triangulate the zero level of grid. ValueError when the grid is not a level set-like
/// FloatGrid (no active voxels is fine: the mesh is empty).
TriangleMesh meshLevelSet(const openvdb::FloatGrid& grid, Mesher mesher = Mesher::MarchingCubes,
                          MeshStats* stats = nullptr);

/// Read a level set from a .vdb file: the float grid named gridName, or (empty name) the first
/// grid of class level set, else the first float grid. InputError naming the file otherwise.
openvdb::FloatGrid::Ptr readLevelSet(const std::string& path, const std::string& gridName = "");

} // namespace fluidsurf
