// OpenMeshDecimate.h - OpenMesh's serial quadric decimater: the thesis' reference (§5.2.1) and
// the baseline our own decimation is measured against. OpenMesh types stay in the .cc.
#pragma once

#include <fluidsurf/Mesh.h>

#include <cstddef>

namespace fluidsurf {
namespace post {

/// OpenMesh's DecimaterT with ModQuadric (Garland-Heckbert error, no bound) and
/// ModNormalFlipping (no collapse turns a face over), collapsing edges, cheapest first, until
/// at most targetTriangles remain (fewer legal collapses stop it earlier). The result is compact
/// (no unused vertices), without normals (Normals.h). ValueError for a mesh OpenMesh cannot take
/// (a non-manifold triangle).
TriangleMesh decimateOpenMesh(const TriangleMesh& mesh, size_t targetTriangles);

} // namespace post
} // namespace fluidsurf
