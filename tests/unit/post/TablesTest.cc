// TablesTest.cc - the vertex -> triangle table (post/Normals.h) and the components
// (post/Volumes.h), both made on all threads with atomics, against plain one-thread references
// written out here: the same lists in triangle order and the same component numbers, for any
// thread count, on meshes big enough that the threads really meet.
#include "post/Normals.h"
#include "post/Volumes.h"

#include <tbb/global_control.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <numeric>
#include <random>
#include <vector>

namespace fluidsurf {
namespace {

using Tri = std::array<uint32_t, 3>;

/// Many small closed pieces (tetrahedra) with their points numbered at random, some points
/// used by none, and a few degenerate triangles (a corner twice), all in shuffled order.
TriangleMesh scrambledTetrahedra(size_t pieces, uint64_t seed)
{
    std::mt19937_64 rng(seed);
    const size_t nv = 4 * pieces + pieces / 3; // the last pieces / 3 points: unused
    std::vector<uint32_t> name(nv);
    std::iota(name.begin(), name.end(), 0u);
    std::shuffle(name.begin(), name.end(), rng);
    TriangleMesh m;
    m.points.resize(nv);
    std::uniform_real_distribution<float> u(-1, 1);
    for (auto& p : m.points)
        p = Vec3f(u(rng), u(rng), u(rng));
    for (size_t k = 0; k < pieces; ++k) {
        const uint32_t a = name[4 * k], b = name[4 * k + 1], c = name[4 * k + 2],
                       d = name[4 * k + 3];
        m.triangles.push_back({a, b, c});
        m.triangles.push_back({a, c, d});
        m.triangles.push_back({a, d, b});
        m.triangles.push_back({b, d, c});
        if (k % 97 == 0) m.triangles.push_back({a, a, b}); // degenerate: a twice
    }
    std::shuffle(m.triangles.begin(), m.triangles.end(), rng);
    return m;
}

/// Each vertex's triangles in triangle order, one corner at a time (a triangle with a corner
/// twice is listed twice).
std::vector<std::vector<uint32_t>> referenceTable(const std::vector<Tri>& tris, uint32_t first,
                                                  uint32_t last)
{
    std::vector<std::vector<uint32_t>> out(last - first);
    for (size_t t = 0; t < tris.size(); ++t)
        for (uint32_t v : tris[t])
            if (v >= first && v < last) out[v - first].push_back(uint32_t(t));
    return out;
}

TEST(VertexTriangles, TheSameListsInTriangleOrderOnAnyThreadCount)
{
    const TriangleMesh m = scrambledTetrahedra(60000, 3);
    const uint32_t nv = uint32_t(m.points.size());
    for (const auto& [first, last] :
         {std::pair<uint32_t, uint32_t>{0, nv}, {nv / 3, 2 * nv / 3}, {0, 1}, {nv - 5, nv}}) {
        const auto want = referenceTable(m.triangles, first, last);
        for (int threads : {1, 2, 8}) {
            tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
            const post::VertexTriangles got(m.triangles, first, last);
            ASSERT_EQ(got.start.size(), size_t(last - first) + 1);
            size_t differ = 0;
            for (uint32_t v = 0; v < last - first; ++v) {
                const std::vector<uint32_t> list(got.tris.begin() + got.start[v],
                                                 got.tris.begin() + got.start[v + 1]);
                differ += list != want[v];
            }
            EXPECT_EQ(differ, 0u) << "vertices " << first << "-" << last << ", " << threads
                                  << " threads";
        }
    }
}

TEST(Components, NumberedByTheirLowestPointOnAnyThreadCount)
{
    const size_t pieces = 50000;
    TriangleMesh m = scrambledTetrahedra(pieces, 5);
    // join every tenth piece to the next by a shared triangle's worth of edges, so that sets
    // merge across the threads' ranges too
    const size_t n = m.triangles.size();
    for (size_t t = 0; t + 40 < n; t += 40)
        m.triangles.push_back({m.triangles[t][0], m.triangles[t + 40][1], m.triangles[t][2]});
    // reference: components by a breadth-first walk from each point in point order
    const size_t nv = m.points.size();
    std::vector<std::vector<uint32_t>> nbr(nv);
    std::vector<uint8_t> used(nv, 0);
    for (const Tri& t : m.triangles)
        for (int k = 0; k < 3; ++k) {
            used[t[k]] = 1;
            nbr[t[k]].push_back(t[(k + 1) % 3]), nbr[t[(k + 1) % 3]].push_back(t[k]);
        }
    std::vector<uint32_t> want(nv, post::kNoComponent);
    uint32_t count = 0;
    for (uint32_t v = 0; v < nv; ++v) {
        if (!used[v] || want[v] != post::kNoComponent) continue;
        std::vector<uint32_t> todo{v};
        want[v] = count;
        while (!todo.empty()) {
            const uint32_t x = todo.back();
            todo.pop_back();
            for (uint32_t y : nbr[x])
                if (want[y] == post::kNoComponent) want[y] = count, todo.push_back(y);
        }
        ++count;
    }
    ASSERT_GT(count, pieces / 2); // many components, most of them joined pairs or runs
    for (int threads : {1, 2, 8}) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        const post::Components c = post::findComponents(m);
        EXPECT_EQ(c.volume.size(), count) << threads << " threads";
        EXPECT_TRUE(c.ofPoint == want) << threads << " threads";
    }
}

} // namespace
} // namespace fluidsurf
