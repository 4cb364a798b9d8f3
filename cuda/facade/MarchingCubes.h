// MarchingCubes.h - marching cubes on the GPU (host facade, no CUDA syntax): the CPU mesher's
// passes (lib/src/mesh/MarchingCubes.h) over the same leaves, in the same order, with the same
// arithmetic (no FMA contraction; the cell and gradient math is the shared mesh/CellPolygons.h
// and mesh/GradientMath.h), so the vertices, normals and triangles come out bit for bit as the
// CPU's, before its last step (vertices no triangle uses are dropped by the caller).
//
// In: the band's leaves as plain arrays (origin, active words, active values in voxel order).
// The device finds each leaf's 26 neighbours by sorting their keys (21 bits a leaf axis), then
// runs one thread a leaf: crossing edges and their prefix sums, the cells' triangle counts and
// theirs, then (finish) the vertices and the triangles straight into the caller's arrays.
#pragma once

#include <fluidsurf/Vec3.h>

#include <cstddef>
#include <cstdint>
#include <memory>

namespace fluidsurf {
namespace cuda {

struct MeshInput
{
    const int32_t* leafOrigins = nullptr; ///< 3 per leaf: index of the leaf's first voxel
    const uint64_t* leafActive = nullptr; ///< 8 per leaf: active voxels (word x, bit y * 8 + z)
    const uint64_t* valueStart = nullptr; ///< leafCount + 1: each leaf's first value in values
    const float* values = nullptr;        ///< the active voxels' values, leaf by leaf, in order
    size_t leafCount = 0;
    /// The leaves' keys: leaf coordinates (origin / 8) minus this, each in [0, 2^21 - 2)
    /// (leafKeysFit says whether a band's leaves allow it).
    int32_t keyOrigin[3] = {0, 0, 0};
    /// index -> world: w = linearT * p + translation; normals: jacobianInverseT * gradient
    /// (row-major 3x3, the transposes OpenVDB's affine map applies, as the CPU mesher does).
    double linearT[9] = {}, translation[3] = {}, jacobianInverseT[9] = {};
    bool normals = true;
};

/// Whether leaves spanning [lo, hi] (leaf coordinates, origin / 8) fit the device's keys.
bool leafKeysFit(const int32_t lo[3], const int32_t hi[3]);

/// One meshing: the constructor uploads and counts (edges, cells), after which the input's
/// arrays may be freed; finish() places the vertices, writes the triangles and downloads them.
/// Throws fluidsurf::Error on CUDA errors.
class MarchingCubesRun
{
public:
    explicit MarchingCubesRun(const MeshInput& input, void* stream = nullptr);
    ~MarchingCubesRun();
    MarchingCubesRun(const MarchingCubesRun&) = delete;
    MarchingCubesRun& operator=(const MarchingCubesRun&) = delete;

    uint64_t vertexCount() const; ///< edge vertices, then the cells' centre vertices
    uint64_t triangleCount() const;
    uint64_t cellCount() const; ///< cells with a sign change that were triangulated
    size_t deviceBytes() const; ///< peak device memory

    /// points: vertexCount(); normals: vertexCount() or null (input.normals false); triangles:
    /// 3 * triangleCount().
    void finish(Vec3f* points, Vec3f* normals, uint32_t* triangles);

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace cuda
} // namespace fluidsurf
