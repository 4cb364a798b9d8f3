// OpenMeshDecimate.h - OpenMesh's serial quadric decimater: the thesis' reference (§5.2.1) and
// the baseline our own decimation is measured against. OpenMesh types stay in the .cc.
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/Mesh.h>

#include <cstddef>

namespace fluidsurf {
namespace post {

/// OpenMesh's DecimaterT with ModQuadric (Garland-Heckbert error, no bound) and
/// ModNormalFlipping (no collapse turns a face over), collapsing edges, cheapest first, until
/// at most targetTriangles remain (fewer legal collapses stop it earlier). The result is compact
/// (no unused vertices), without normals (Normals.h). ValueError for a mesh OpenMesh cannot take
/// (a non-manifold triangle).
/// ctx's checkpoint every 1000 collapses: a cancel stops the decimater and throws Cancelled
/// (it went on for its minutes, signals or not).
TriangleMesh decimateOpenMesh(const TriangleMesh& mesh, size_t targetTriangles, Context& ctx);

} // namespace post
} // namespace fluidsurf
