// CollapseCracksTest.cc - merging a crack's level-3 points into its level-2 edge, on hand-made
// planar sheets where each outcome can be worked out on paper: a merge that closes the crack,
// one refused because a triangle would turn over, one refused because an edge would get a third
// and fourth triangle, and a point that shares no triangle with the end it belongs to.
#include "adaptive/CollapseCracks.h"

#include <fluidsurf/MeshCheck.h>

#include <gtest/gtest.h>

namespace fluidsurf {
namespace {

using adaptive::CrackPath;

/// The mesh without the triangles marked removed.
TriangleMesh without(const TriangleMesh& mesh, const std::vector<char>& removed)
{
    TriangleMesh out;
    out.points = mesh.points;
    for (size_t t = 0; t < mesh.triangles.size(); ++t)
        if (!removed[t]) out.triangles.push_back(mesh.triangles[t]);
    return out;
}

/// In the plane z = 0, seen from +z (counter-clockwise): above the edge a -> b a level-2
/// triangle (a, b, c); below it a level-3 fan around m, whose crack edges are b -> m -> a, so the
/// crack is a -> b against b -> m -> a. m is nearer a, so it belongs to a. d1 and d2 are the fan's
/// other corners.
enum Vertex : uint32_t { A, B, C, M, D1, D2, G };
TriangleMesh crack(Vec3f d1)
{
    TriangleMesh mesh;
    mesh.points = {{0, 0, 0}, {2, 0, 0}, {1, 1, 0}, {0.9f, -0.1f, 0}, d1, {1, -1, 0}};
    mesh.triangles = {{A, B, C}, {M, A, D1}, {M, D1, D2}, {M, D2, B}};
    return mesh;
}

TEST(CollapseCracks, APointMergesIntoItsEndAndClosesTheCrack)
{
    TriangleMesh mesh = crack({0.3f, -1, 0});
    ASSERT_EQ(checkMesh(mesh).misorientedEdges, 0u);
    const size_t openBefore = checkMesh(mesh).boundaryEdges;
    std::vector<CrackPath> paths{{A, B, {M}}};
    std::vector<char> removed;
    EXPECT_EQ(adaptive::collapseCracks(mesh, paths, removed), 1u);
    EXPECT_TRUE(paths[0].between.empty());
    // (m, a, d1) flattens; the other two turn into (a, d1, d2) and (a, d2, b).
    ASSERT_EQ(removed, (std::vector<char>{0, 1, 0, 0}));
    const TriangleMesh after = without(mesh, removed);
    EXPECT_EQ(after.triangles[1], (std::array<uint32_t, 3>{A, D1, D2}));
    EXPECT_EQ(after.triangles[2], (std::array<uint32_t, 3>{A, D2, B}));
    const MeshReport report = checkMesh(after);
    EXPECT_EQ(report.boundaryEdges, openBefore - 3); // a-b, b-m and m-a: one edge, closed
    EXPECT_EQ(report.misorientedEdges + report.nonManifoldEdges + report.degenerateTriangles, 0u);
}

TEST(CollapseCracks, AMergeThatWouldTurnATriangleOverIsRefused)
{
    // d1 just below the crack near a: (m, d1, d2) would become (a, d1, d2), clockwise.
    TriangleMesh mesh = crack({0.5f, -0.15f, 0});
    ASSERT_EQ(checkMesh(mesh).misorientedEdges, 0u);
    const TriangleMesh before = mesh;
    std::vector<CrackPath> paths{{A, B, {M}}};
    std::vector<char> removed;
    EXPECT_EQ(adaptive::collapseCracks(mesh, paths, removed), 0u);
    EXPECT_EQ(paths[0].between, (std::vector<uint32_t>{M})); // left for cutting (a, b, c)
    EXPECT_EQ(removed, std::vector<char>(4, 0));
    EXPECT_EQ(mesh.triangles, before.triangles);
}

TEST(CollapseCracks, AMergeThatWouldGiveAnEdgeMoreThanTwoTrianglesIsRefused)
{
    // A second sheet through a and d2, off the plane: edge a-d2 has its two triangles already,
    // and (m, d2, b) would bring two more.
    TriangleMesh mesh = crack({0.3f, -1, 0});
    mesh.points.push_back({0.5f, -0.5f, 1}); // g
    mesh.points.push_back({0.5f, -0.5f, -1});
    mesh.triangles.push_back({A, D2, G});
    mesh.triangles.push_back({D2, A, G + 1});
    std::vector<CrackPath> paths{{A, B, {M}}};
    std::vector<char> removed;
    EXPECT_EQ(adaptive::collapseCracks(mesh, paths, removed), 0u);
    EXPECT_EQ(paths[0].between, (std::vector<uint32_t>{M}));
    EXPECT_EQ(removed, std::vector<char>(6, 0));
}

TEST(CollapseCracks, APointThatSharesNoTriangleWithItsEndStays)
{
    // m's fan without the triangle at a: m is next to b only, and it is nearer a.
    TriangleMesh mesh = crack({0.3f, -1, 0});
    mesh.triangles = {{A, B, C}, {M, D1, D2}, {M, D2, B}};
    std::vector<CrackPath> paths{{A, B, {M}}};
    std::vector<char> removed;
    EXPECT_EQ(adaptive::collapseCracks(mesh, paths, removed), 0u);
    EXPECT_EQ(paths[0].between, (std::vector<uint32_t>{M}));
}

} // namespace
} // namespace fluidsurf
