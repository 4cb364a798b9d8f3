// NormalsTest.cc - angle-weighted vertex normals (post/Normals): exact on a cube however its
// faces are cut, radial on a sphere, outward, and the same bits for any thread count.
#include "post/Normals.h"

#include "post/IsolatedSpheres.h"
#include <fluidsurf/MeshCheck.h>

#include <tbb/global_control.h>

#include <gtest/gtest.h>

#include <cmath>

namespace fluidsurf {
namespace {

/// The unit cube [0,1]^3, each face cut into two triangles along a diagonal that alternates
/// from face to face, counter-clockwise seen from outside.
TriangleMesh cube()
{
    TriangleMesh m;
    for (int i = 0; i < 8; ++i)
        m.points.emplace_back(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
    // faces as corner quads counter-clockwise from outside; even faces cut 0-2, odd 1-3
    const uint32_t quads[6][4] = {{0, 2, 3, 1}, {4, 5, 7, 6}, {0, 1, 5, 4},
                                  {2, 6, 7, 3}, {0, 4, 6, 2}, {1, 3, 7, 5}};
    for (int f = 0; f < 6; ++f) {
        const uint32_t* q = quads[f];
        if (f % 2 == 0) {
            m.triangles.push_back({q[0], q[1], q[2]});
            m.triangles.push_back({q[0], q[2], q[3]});
        } else {
            m.triangles.push_back({q[0], q[1], q[3]});
            m.triangles.push_back({q[1], q[2], q[3]});
        }
    }
    return m;
}

TEST(Normals, CubeCornersPointAlongTheirDiagonalsHoweverTheFacesAreCut)
{
    TriangleMesh m = cube();
    const MeshReport r = checkMesh(m);
    ASSERT_TRUE(r.watertight()) << describe(r);
    ASSERT_NEAR(r.volume, 1.0, 1e-9); // outward
    // area weights would tilt the corners where a face's diagonal ends (two triangles there)
    post::computeAngleWeightedNormals(m);
    ASSERT_EQ(m.normals.size(), 8u);
    const float s = float(1 / std::sqrt(3.0));
    for (size_t i = 0; i < 8; ++i) {
        // outward: away from the cube's centre along each axis
        const Vec3f expected((m.points[i].x * 2 - 1) * s, (m.points[i].y * 2 - 1) * s,
                             (m.points[i].z * 2 - 1) * s);
        EXPECT_NEAR(m.normals[i].x, expected.x, 1e-6) << i;
        EXPECT_NEAR(m.normals[i].y, expected.y, 1e-6) << i;
        EXPECT_NEAR(m.normals[i].z, expected.z, 1e-6) << i;
    }
}

TEST(Normals, SphereNormalsAreRadialAndTheSameForAnyThreadCount)
{
    TriangleMesh m = post::unitIcosphere(4);
    m.normals.clear();
    m.points.push_back(Vec3f(9, 9, 9)); // no triangle uses it: zero normal
    post::computeAngleWeightedNormals(m);
    for (size_t i = 0; i + 1 < m.points.size(); ++i) {
        const Vec3f& p = m.points[i];
        const Vec3f& n = m.normals[i];
        const double cosine = (double(p.x) * n.x + double(p.y) * n.y + double(p.z) * n.z);
        ASSERT_GT(cosine, std::cos(0.5 * M_PI / 180)) << i; // within half a degree
    }
    EXPECT_EQ(m.normals.back(), Vec3f(0, 0, 0));
    TriangleMesh one = m;
    {
        tbb::global_control single(tbb::global_control::max_allowed_parallelism, 1);
        post::computeAngleWeightedNormals(one);
    }
    EXPECT_EQ(one.normals, m.normals);
}

} // namespace
} // namespace fluidsurf
