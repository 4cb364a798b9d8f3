// PlaneQuadricsTest.cc - each vertex's quadric from its triangles' planes (post/PlaneQuadrics.h),
// one vertex at a time and four at a time in AVX registers, against a reference written out
// here from the rule itself: for every triangle that has the vertex as a corner, in mesh order
// (twice for a triangle with it at two corners), the plane through the first corner with the
// unit normal of the sides' cross product, weighted by half the cross product's length, about
// the vertex's point; then packed. The packed bytes must be the same, whatever the vertices'
// valences (the lanes of a group run past their vertex's last triangle), with triangles without
// area, unused vertices, ranges whose length is no multiple of four, and a table for a part of
// the vertices.
#include "post/PlaneQuadrics.h"

#include "util/Lanes.h"

#include <fluidsurf/Error.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

namespace fluidsurf {
namespace {

using Tri = std::array<uint32_t, 3>;
using post::PackedQuadric;
using post::Quadric;

PackedQuadric reference(const std::vector<Vec3d>& p, const std::vector<Tri>& tris, uint32_t v)
{
    Quadric q{};
    for (const Tri& t : tris)
        for (uint32_t corner : t) {
            if (corner != v) continue;
            const Vec3d a = p[t[0]], e1 = p[t[1]] - a, e2 = p[t[2]] - a;
            const Vec3d n(e1[1] * e2[2] - e1[2] * e2[1], e1[2] * e2[0] - e1[0] * e2[2],
                          e1[0] * e2[1] - e1[1] * e2[0]);
            const double len = std::sqrt(n[0] * n[0] + n[1] * n[1] + n[2] * n[2]);
            if (!(len > 0)) continue;
            const Vec3d u(n[0] / len, n[1] / len, n[2] / len), x = a - p[v];
            const double w = len / 2, d = -(u[0] * x[0] + u[1] * x[1] + u[2] * x[2]);
            q.a00 += w * u[0] * u[0], q.a01 += w * u[0] * u[1], q.a02 += w * u[0] * u[2];
            q.a11 += w * u[1] * u[1], q.a12 += w * u[1] * u[2], q.a22 += w * u[2] * u[2];
            q.b0 += w * d * u[0], q.b1 += w * d * u[1], q.b2 += w * d * u[2];
            q.c += w * d * d, q.w += w;
        }
    return PackedQuadric::pack(q);
}

/// Points on a wavy sheet, triangles among near neighbours (valences from 0 to a few dozen),
/// some of them without area: a corner twice, or three corners on a line.
void randomMesh(uint64_t seed, std::vector<Vec3d>& p, std::vector<Tri>& tris)
{
    std::mt19937_64 rng(seed);
    std::uniform_real_distribution<double> u(-1, 1);
    const uint32_t n = 203;
    p.resize(n);
    for (auto& x : p)
        x = Vec3d(u(rng), u(rng), 0.1 * u(rng));
    for (int k = 0; k < 700; ++k) {
        // a hub with many triangles: vertex 7 in every fifth
        const uint32_t a = k % 5 == 0 ? 7 : uint32_t(rng() % (n - 3)),
                       b = uint32_t(rng() % (n - 3)),
                       c = uint32_t(rng() % (n - 3)); // the last three: used by none
        if (k % 37 == 5)
            tris.push_back({a, b, a}); // a corner twice
        else
            tris.push_back({a, b, c});
    }
    // three corners on a line: an exact zero cross product
    p[20] = Vec3d(0.25, 0.5, 0.125), p[21] = Vec3d(0.5, 1.0, 0.25), p[22] = Vec3d(0.75, 1.5, 0.375);
    tris.push_back({20, 21, 22});
    tris.push_back({21, 22, 20});
}

} // namespace

TEST(PlaneQuadrics, EachVertexGetsItsTrianglesPlanesInOrderOnEveryRegisterWidth)
{
    std::vector<int> widths{1};
    if (util::doubleRegisterLanes() == 4) widths.push_back(4);
    for (uint64_t seed = 1; seed <= 4; ++seed) {
        std::vector<Vec3d> p;
        std::vector<Tri> tris;
        randomMesh(seed, p, tris);
        const auto n = uint32_t(p.size());
        std::vector<PackedQuadric> expected(n);
        for (uint32_t v = 0; v < n; ++v)
            expected[v] = reference(p, tris, v);
        // the whole table, and a part of it (vertices [first, last) only)
        for (const auto& [first, last] : {std::pair<uint32_t, uint32_t>{0, n}, {37, 151}}) {
            const post::VertexTriangles around(tris, first, last);
            for (int lanes : widths)
                for (const auto& [begin, end] : {std::pair<uint32_t, uint32_t>{first, last},
                                                 {first + 1, first + 4},
                                                 {first + 3, last - 2}}) {
                    std::vector<PackedQuadric> got(n);
                    post::planeQuadrics(p.data(), tris, around, first, begin, end, got.data(),
                                        lanes);
                    for (uint32_t v = begin; v < end; ++v)
                        ASSERT_EQ(0, std::memcmp(&got[v], &expected[v], sizeof got[v]))
                            << "vertex " << v << ", " << lanes << " at a time, seed " << seed;
                }
        }
    }
}

TEST(PlaneQuadrics, RefusesOtherWidths)
{
    const std::vector<Vec3d> p(3, Vec3d(0.0));
    const std::vector<Tri> tris{{0, 1, 2}};
    const post::VertexTriangles around(tris, 0, 3);
    PackedQuadric out[3];
    EXPECT_THROW(post::planeQuadrics(p.data(), tris, around, 0, 0, 3, out, 2), ValueError);
    EXPECT_THROW(post::planeQuadrics(p.data(), tris, around, 0, 0, 3, out, 8), ValueError);
}

} // namespace fluidsurf
