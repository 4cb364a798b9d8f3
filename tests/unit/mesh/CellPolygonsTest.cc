// CellPolygonsTest.cc - a cell's polygons looked up by its corners' signs (the host's table) are
// those cut from its values, for every sign pattern and random values, and so are the counting
// pass' triangles and the writing pass' fans; and, independently of both, every crossing edge lies
// on one polygon, each step along a face of both its edges.
#include "mesh/CellPolygons.h"

#include <gtest/gtest.h>

#include <array>
#include <random>
#include <vector>

using namespace fluidsurf::mesh;

namespace {

/// Whether edge e (corners a, b) is one of face f's four sides.
bool onFace(int e, int f)
{
    for (int k = 0; k < 4; ++k)
        if (kEdges.index[kFace[f][k]][kFace[f][(k + 1) & 3]] == e) return true;
    return false;
}

} // namespace

TEST(CellPolygons, LookedUpAsCutForEverySignPattern)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> magnitude(1e-6f, 2.f);
    int fourCrossingCells = 0;
    for (int pattern = 0; pattern < 256; ++pattern)
        for (int trial = 0; trial < 40; ++trial) {
            float c[8];
            for (int n = 0; n < 8; ++n)
                c[n] = (pattern >> n & 1 ? -1.f : 1.f) * magnitude(rng);
            const CellPolygons looked(c);
            CellPolygons cut;
            cut.cut(c);
            fourCrossingCells += cut.ambiguous;
            ASSERT_EQ(looked.ambiguous, cut.ambiguous) << pattern;
            // the counting pass' triangles: the cut polygons fanned, n - 2 each
            int fanned = 0;
            std::vector<std::array<int, 3>> fan; // the cut polygons fanned from their first edge
            cut.forEach([&](const int* edges, int n) {
                fanned += n - 2;
                for (int k = 1; k + 1 < n; ++k)
                    fan.push_back({edges[0], edges[k], edges[k + 1]});
            });
            ASSERT_EQ(cellTriangles(c), cut.ambiguous ? -1 : fanned) << pattern;
            // the writing pass' triangles: the same edges in the same order
            const CellFan table = cellFan(c);
            ASSERT_EQ(table.polygons != nullptr, !cut.ambiguous) << pattern;
            if (table.polygons) {
                ASSERT_EQ(table.count, int(fan.size())) << pattern;
                for (int t = 0; t < table.count; ++t)
                    for (int k = 0; k < 3; ++k)
                        ASSERT_EQ(table.triangles[t][k], fan[size_t(t)][size_t(k)])
                            << pattern << " triangle " << t;
            }
            int before[12] = {}; // each crossing edge follows one other: closed polygons
            for (int e = 0; e < 12; ++e)
                if (looked.next[e] >= 0) ++before[looked.next[e]];
            for (int e = 0; e < 12; ++e) {
                ASSERT_EQ(before[e], looked.next[e] >= 0 ? 1 : 0) << pattern << " " << e;
                ASSERT_EQ(looked.next[e], cut.next[e]) << "pattern " << pattern << " edge " << e;
                if (cut.next[e] >= 0) ASSERT_EQ(looked.face[e], cut.face[e]) << pattern;
                // every edge with a sign change, and only those, is on a polygon, and the step
                // to the next lies on a face of both
                const int a = kEdges.lowCorner[e], b = a | 1 << kEdges.axis[e];
                const bool crosses = (pattern >> a & 1) != (pattern >> b & 1);
                ASSERT_EQ(looked.next[e] >= 0, crosses) << pattern << " " << e;
                if (crosses) {
                    ASSERT_TRUE(onFace(e, looked.face[e]) && onFace(looked.next[e], looked.face[e]))
                        << pattern << " " << e;
                }
            }
        }
    EXPECT_GT(fourCrossingCells, 0); // the values' path was taken too
}
