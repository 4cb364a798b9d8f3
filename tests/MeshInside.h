// MeshInside.h - which points a closed triangle mesh encloses, by ray parity: independent of the
// library's fields and meshers, for tests that ask whether the particles lie inside the surface.
#pragma once

#include <fluidsurf/Mesh.h>

#include <vector>

namespace fluidsurf {
namespace test {

/// For each point, whether a ray from it along +z crosses the mesh an odd number of times
/// (triangles binned by their x-y bounds). For a closed mesh: inside. A ray through an edge or a
/// vertex exactly can miscount; jittered points make that vanishingly rare.
std::vector<bool> insideMesh(const TriangleMesh& mesh, const std::vector<Vec3f>& points);

} // namespace test
} // namespace fluidsurf
