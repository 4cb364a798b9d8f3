// TablesTest.cc - the vertex -> triangle table (post/Normals.h) and the components
// (post/Volumes.h), both made on all threads with atomics, against plain one-thread references
// written out here: the same lists in triangle order, the same component numbers and the same
// closed ones, for any thread count, on meshes big enough that the threads really meet.
#include "post/Normals.h"
#include "post/Volumes.h"

#include <tbb/global_control.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <map>
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
        for (int threads : {1, 2, 8, 16}) {
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

TEST(Components, ClosedWhereEverySideHasTwoTriangles)
{
    // closed tetrahedra, with pieces opened (a triangle taken out), made non-manifold (a
    // triangle twice: its sides three times) and given a triangle with a corner twice (its
    // side from that corner to itself once)
    TriangleMesh m = scrambledTetrahedra(40000, 7);
    std::vector<Tri> kept;
    for (size_t t = 0; t < m.triangles.size(); ++t) {
        if (t % 53 == 0) continue;
        kept.push_back(m.triangles[t]);
        if (t % 71 == 0) kept.push_back(m.triangles[t]);
    }
    m.triangles = kept;
    // and a piece of two triangles with a corner twice, whose every side has two (closed, as
    // the sides are counted: each triangle's sides once, however often a corner repeats)
    const auto p = uint32_t(m.points.size());
    m.points.insert(m.points.end(), {Vec3f(0, 0, 0), Vec3f(1, 0, 0), Vec3f(0, 1, 0)});
    m.triangles.push_back({p, p, p + 1});
    m.triangles.push_back({p + 2, p, p});
    // reference: every side of every triangle counted in a map, one thread
    std::map<std::pair<uint32_t, uint32_t>, int> count;
    for (const Tri& t : m.triangles)
        for (int k = 0; k < 3; ++k)
            ++count[std::minmax(t[k], t[(k + 1) % 3])];
    const post::Components found = post::findComponents(m);
    std::vector<uint8_t> want(found.volume.size(), 1);
    for (const auto& [side, n] : count)
        if (n != 2) want[found.ofPoint[side.first]] = 0;
    const size_t open = size_t(std::count(want.begin(), want.end(), uint8_t(0)));
    ASSERT_GT(open, want.size() / 20); // each kind of flaw is there, many times
    ASSERT_LT(open, want.size() / 2);
    ASSERT_TRUE(want[found.ofPoint[p]]);
    for (int threads : {1, 2, 8}) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        post::Components c = found;
        post::markClosed(c, m, c.ofPoint);
        EXPECT_TRUE(c.closed == want) << threads << " threads";
    }
}

} // namespace
} // namespace fluidsurf
