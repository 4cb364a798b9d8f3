// MarchingCubes.h - our marching cubes over the active narrow band of a level set (see
// fluidsurf/MeshLevelSet.h for what it guarantees).
//
// Passes over the VDB leaves, each parallel (TBB) and written per leaf, so the output does not
// depend on the thread count (pass 0 reads each leaf's active and inside bits):
//  1. crossing edges: for every active voxel, which of its +x/+y/+z edges (to an active
//     neighbour) change sign; counted per leaf, prefix-summed into vertex numbers;
//  2. the cells' triangles and centre vertices (below), counted per leaf and prefix-summed, so
//     that the mesh's arrays are made once, at their size, and each leaf writes into its part;
//  3. one vertex per crossing edge (linear interpolation, normal from the gradient), numbered
//     leaf by leaf and voxel by voxel, so that any cell finds its vertices by counting the
//     crossing-edge bits before them (a few popcounts; 224 bytes a leaf);
//  4. triangles: every cell whose 8 corners are active and whose signs differ. Its polygons are
//     traced from face segments (ambiguous faces by the bilinear saddle value) and fanned (around
//     a centre vertex in cells with an ambiguous face; these come after the edge vertices).
// Vertices no complete cell uses (edges at the band's rim) are dropped at the end. Each pass
// calls ctx.checkpoint() once per leaf range.
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/Mesh.h>

#include <openvdb/openvdb.h>

#include <cstdint>

namespace fluidsurf {
namespace mesh {

/// surfaceCells (optional): the number of cells with a sign change that were triangulated.
TriangleMesh marchingCubes(const openvdb::FloatGrid& grid, Context& ctx,
                           size_t* surfaceCells = nullptr,
                           RawNormals normals = RawNormals::Gradient);

/// The grid's index -> world map as the passes apply it (OpenVDB maps multiply row vectors,
/// p * M; the passes compute M^T * p + translation, and M^-T * gradient for normals), for the
/// GPU mesher too, which repeats the same arithmetic.
struct Affine
{
    openvdb::Mat3d linear, jacobianInverse;
    openvdb::Vec3d translation;
    explicit Affine(const openvdb::math::Transform& xform);
};

/// The tree the passes mesh: grid's, or for a grid with active tiles (rare in level sets) a
/// copy, held in keep, whose tiles are inactive and whose voxels where a tile's face can carry
/// the surface are active leaf voxels (ActiveTiles.cc): the voxelized grid's surface, at a cost
/// in the tiles' faces. ValueError past ctx's memory budget, with the estimate.
const openvdb::FloatTree& leafOnlyTree(const openvdb::FloatGrid& grid,
                                       openvdb::FloatTree::Ptr& keep, Context& ctx);

/// ValueError where a mesh would have 2^31 vertices or more (vertex numbers are 32 bits).
void checkVertexCount(uint64_t vertices);

/// Drop vertices no triangle uses and renumber them (order kept): the passes' last step.
void dropUnusedVertices(TriangleMesh& mesh, Context& ctx);

} // namespace mesh
} // namespace fluidsurf
