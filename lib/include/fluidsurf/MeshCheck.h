// MeshCheck.h - the one mesh validity function (DESIGN.md, "Meshes"): every mesh stage and test
// is judged by checkMesh.
#pragma once

#include <fluidsurf/Mesh.h>

#include <cstddef>
#include <string>

namespace fluidsurf {

/// Triangles with an angle under this many degrees are counted as thin (slivers): what
/// post-processing should make fewer (thesis ch. 5, issue 13's acceptance).
constexpr double kThinAngleDegrees = 10;

struct MeshReport
{
    size_t vertices = 0, triangles = 0;
    size_t unusedVertices = 0;      ///< vertices no triangle references
    size_t boundaryEdges = 0;       ///< edges of exactly one triangle
    size_t nonManifoldEdges = 0;    ///< edges of three or more triangles
    size_t nonManifoldVertices = 0; ///< vertices whose triangles form more than one fan
    size_t misorientedEdges = 0;    ///< two-triangle edges walked in the same direction by both
    size_t degenerateTriangles = 0; ///< repeated vertex index or zero area
    size_t components = 0;          ///< connected components (through shared vertices)
    size_t thinTriangles = 0;       ///< non-degenerate, with an angle under kThinAngleDegrees
    double minAngleDegrees = 0;     ///< the smallest angle of a non-degenerate triangle
    double volume = 0;              ///< enclosed volume (signed: > 0 when oriented outward)
    double area = 0;

    /// Closed, manifold, consistently oriented and without degenerate triangles.
    bool watertight() const
    {
        return boundaryEdges == 0 && nonManifoldEdges == 0 && nonManifoldVertices == 0 &&
               misorientedEdges == 0 && degenerateTriangles == 0;
    }
};

MeshReport checkMesh(const TriangleMesh& mesh);

/// The largest distance from a point of mesh a (its vertices and triangle centroids) to mesh
/// b, each exact to b's nearest triangle; +inf when some point is farther than `reach`, the
/// search radius (world units). One side of the Hausdorff distance: the symmetric one is the
/// larger of meshDistance(a, b) and meshDistance(b, a). 0 for an empty a.
double meshDistance(const TriangleMesh& a, const TriangleMesh& b, double reach);

/// The mean distance from the points of mesh a (its vertices and triangle centroids, as above)
/// to mesh b, each exact, a point farther than `reach` counting as reach. 0 for an empty a.
/// The same for any thread count (summed in point order).
double meanMeshDistance(const TriangleMesh& a, const TriangleMesh& b, double reach);

/// One line: "V vertices, T triangles, C components, volume, area, problems (or 'watertight')".
std::string describe(const MeshReport& report);

} // namespace fluidsurf
