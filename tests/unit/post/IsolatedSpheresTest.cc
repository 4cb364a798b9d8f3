// IsolatedSpheresTest.cc - isolated particles as icospheres (post/IsolatedSpheres): the sphere
// of every level is closed, manifold and outward; its deviation from the sphere, measured here
// by sampling each face, is what the level is chosen by; appended spheres are components of
// their own with every vertex at r from their particle.
#include "post/IsolatedSpheres.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/MeshCheck.h>

#include <gtest/gtest.h>

#include <cmath>

namespace fluidsurf {
namespace {

double length(const Vec3f& v)
{
    return std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
}

/// The largest 1 - |x| over a grid of points on each face: an independent estimate of how far
/// the faces dip inside the unit sphere (from below: the grid may miss the deepest point).
double sampledDeviation(const TriangleMesh& m, int steps)
{
    double deepest = 0;
    for (const auto& t : m.triangles)
        for (int i = 0; i <= steps; ++i)
            for (int j = 0; i + j <= steps; ++j) {
                const float a = float(i) / float(steps), b = float(j) / float(steps);
                const Vec3f p =
                    m.points[t[0]] * (1 - a - b) + m.points[t[1]] * a + m.points[t[2]] * b;
                deepest = std::max(deepest, 1.0 - length(p));
            }
    return deepest;
}

TEST(IsolatedSpheres, EveryLevelIsAClosedOutwardSphere)
{
    double previous = 1;
    for (int level = 0; level <= 4; ++level) {
        SCOPED_TRACE("level " + std::to_string(level));
        const TriangleMesh s = post::unitIcosphere(level);
        const size_t f = size_t(20) << (2 * level);
        EXPECT_EQ(s.triangles.size(), f);
        EXPECT_EQ(s.points.size(), f / 2 + 2); // Euler: V - E + F = 2 with E = 3F/2
        const MeshReport r = checkMesh(s);
        EXPECT_TRUE(r.watertight()) << describe(r);
        EXPECT_EQ(r.components, 1u);
        // outward, and between the inscribed volume and the sphere's
        EXPECT_GT(r.volume, 0.6 * 4.0 / 3.0 * M_PI);
        EXPECT_LT(r.volume, 4.0 / 3.0 * M_PI);
        for (size_t i = 0; i < s.points.size(); ++i) {
            EXPECT_NEAR(length(s.points[i]), 1.0, 1e-6);
            EXPECT_EQ(s.normals[i], s.points[i]);
        }
        const double deviation = post::icosphereDeviation(s);
        const double sampled = sampledDeviation(s, 12);
        EXPECT_LE(sampled, deviation + 1e-6);
        EXPECT_GE(sampled, 0.9 * deviation); // the grid comes close to the deepest point
        EXPECT_LT(deviation, previous / 3);  // each level divides it by about four
        previous = deviation;
    }
}

TEST(IsolatedSpheres, LevelForOnePercentIsTheCoarsestWithin)
{
    const int level = post::icosphereLevelFor(0.01);
    EXPECT_LE(post::icosphereDeviation(post::unitIcosphere(level)), 0.01);
    ASSERT_GT(level, 0);
    EXPECT_GT(post::icosphereDeviation(post::unitIcosphere(level - 1)), 0.01);
    EXPECT_THROW(post::icosphereLevelFor(0), ValueError);
    EXPECT_THROW(post::unitIcosphere(-1), ValueError);
}

TEST(IsolatedSpheres, AppendedSpheresAreComponentsOfTheirOwn)
{
    // a mesh to append to: one sphere of radius 1 at the origin, normals set
    TriangleMesh mesh = post::unitIcosphere(2);
    const size_t before = mesh.points.size();
    const std::vector<Vec3f> centres = {{5, 0, 0}, {0, 5, 0}, {-3, -3, 2}};
    const std::vector<float> radii = {0.025f, 0.5f, 2.0f};
    post::appendSpheres(mesh, centres, radii, 3);
    const MeshReport r = checkMesh(mesh);
    EXPECT_TRUE(r.watertight()) << describe(r);
    EXPECT_EQ(r.components, 4u);
    ASSERT_EQ(mesh.normals.size(), mesh.points.size());
    const size_t per = post::unitIcosphere(3).points.size();
    ASSERT_EQ(mesh.points.size(), before + 3 * per);
    for (size_t s = 0; s < 3; ++s)
        for (size_t i = 0; i < per; ++i) {
            const Vec3f p = mesh.points[before + s * per + i];
            EXPECT_NEAR(length(p - centres[s]), radii[s], 0.01 * radii[s]);
        }
    // one radius for all; a mesh without normals gets none
    TriangleMesh bare;
    bare.points = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}};
    bare.triangles = {{0, 1, 2}};
    post::appendSpheres(bare, centres, {0.1f}, 1);
    EXPECT_TRUE(bare.normals.empty());
    EXPECT_EQ(bare.points.size(), 3 + 3 * post::unitIcosphere(1).points.size());
    EXPECT_THROW(post::appendSpheres(bare, centres, {1.f, 2.f}, 1), ValueError);
}

} // namespace
} // namespace fluidsurf
