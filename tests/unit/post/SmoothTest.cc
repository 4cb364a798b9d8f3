// SmoothTest.cc - bounded smoothing along the normals (post/Smooth): a bumpy sphere comes out
// rounder with no point moved past the bound, a spike is held at the bound, open borders stay,
// and the same bits come out for any thread count. The flattening: bumps several voxels wide
// that Taubin's rounds leave are taken out of a flat sheet, a small curved body is left to
// Taubin's rounds alone, a large one keeps its volume.
#include "post/Smooth.h"
#include "GridMesh.h"
#include "post/IsolatedSpheres.h"

#include <fluidsurf/MeshCheck.h>

#include <tbb/global_control.h>

#include <gtest/gtest.h>

#include <cmath>

namespace fluidsurf {
namespace {

double length(const Vec3f& v)
{
    return std::sqrt(double(v.x) * v.x + double(v.y) * v.y + double(v.z) * v.z);
}

/// The unit icosphere of `level` with every point pushed out or in by up to `bump` (a fixed
/// hash of its index, not a random generator: the same mesh everywhere).
TriangleMesh bumpySphere(double bump, int level = 4)
{
    TriangleMesh m = post::unitIcosphere(level);
    for (size_t v = 0; v < m.points.size(); ++v) {
        const double u = double((v * 2654435761u) % 1000) / 999.0; // in [0, 1]
        m.points[v] = m.points[v] * float(1 + bump * (2 * u - 1));
    }
    return m;
}

double radiusSpread(const TriangleMesh& m)
{
    double sum = 0, sum2 = 0;
    for (const Vec3f& p : m.points)
        sum += length(p), sum2 += length(p) * length(p);
    const double n = double(m.points.size()), mean = sum / n;
    return std::sqrt(std::max(0.0, sum2 / n - mean * mean));
}

TEST(Smooth, BumpySphereComesOutRounderWithinTheBound)
{
    const TriangleMesh bumpy = bumpySphere(0.02);
    const double bound = 0.03;
    const TriangleMesh s = post::smoothAlongNormals(bumpy, 6, bound);
    ASSERT_EQ(s.points.size(), bumpy.points.size());
    EXPECT_EQ(s.triangles, bumpy.triangles);
    EXPECT_LT(radiusSpread(s), 0.5 * radiusSpread(bumpy)); // 36% here
    for (size_t v = 0; v < s.points.size(); ++v)
        ASSERT_LE(length(s.points[v] - bumpy.points[v]), bound + 1e-6) << v;
    const MeshReport before = checkMesh(bumpy), after = checkMesh(s);
    EXPECT_TRUE(after.watertight()) << describe(after);
    EXPECT_NEAR(after.volume, before.volume, 0.01 * before.volume);
    EXPECT_TRUE(s.normals.empty()); // moved points: the old normals would be stale
    // no rounds, or no room to move: the mesh as it was
    EXPECT_EQ(post::smoothAlongNormals(bumpy, 0, bound).points, bumpy.points);
    EXPECT_EQ(post::smoothAlongNormals(bumpy, 6, 0.0).points, bumpy.points);
}

TEST(Smooth, SpikeIsHeldAtTheBound)
{
    TriangleMesh spiky = post::unitIcosphere(3);
    spiky.points[0] = spiky.points[0] * 1.5f; // a tip half a radius out
    const double bound = 0.05;
    const TriangleMesh free = post::smoothAlongNormals(spiky, 6, 10.0);
    const TriangleMesh held = post::smoothAlongNormals(spiky, 6, bound);
    // unbounded, the tip is pulled well in; bounded, it moves exactly the bound
    EXPECT_GT(length(free.points[0] - spiky.points[0]), 4 * bound);
    EXPECT_NEAR(length(held.points[0] - spiky.points[0]), bound, 1e-6);
    EXPECT_GT(length(held.points[0]), 1.4);
}

TEST(Smooth, OpenBorderStaysAndTheInsideFlattens)
{
    // a 16 x 16 grid of unit squares in z = 0 with its inner points raised or lowered by 0.1
    const uint32_t n = 16;
    const TriangleMesh m = test::gridMesh(n, [&](uint32_t i, uint32_t j) {
        const bool border = i == 0 || j == 0 || i == n || j == n;
        return border ? 0.0 : (i + j) % 2 ? 0.1 : -0.1;
    });
    const TriangleMesh s = post::smoothAlongNormals(m, 6, 0.5);
    double before = 0, after = 0;
    for (uint32_t j = 0; j <= n; ++j)
        for (uint32_t i = 0; i <= n; ++i) {
            const uint32_t v = j * (n + 1) + i;
            if (i == 0 || j == 0 || i == n || j == n) {
                EXPECT_EQ(s.points[v], m.points[v]) << i << "," << j;
                continue;
            }
            before += double(m.points[v].z) * m.points[v].z;
            after += double(s.points[v].z) * s.points[v].z;
            // along the normal: a flat patch's normal is z, so x and y stay
            EXPECT_NEAR(s.points[v].x, m.points[v].x, 0.02);
            EXPECT_NEAR(s.points[v].y, m.points[v].y, 0.02);
        }
    EXPECT_LT(after, 0.1 * before);
}

/// A 64 x 64 grid of unit squares in z = 0 (open: its border stays) with bumps 8 units wide,
/// z = a sin(2 pi x / 8) sin(2 pi y / 8), and a finer jitter on top.
TriangleMesh wavySheet(double a)
{
    const uint32_t n = 64;
    const double k = 2 * M_PI / 8;
    return test::gridMesh(n, [&](uint32_t i, uint32_t j) {
        const uint32_t v = j * (n + 1) + i;
        const double jitter = 0.02 * (double((v * 2654435761u) % 1000) / 999.0 - 0.5);
        const bool border = i == 0 || j == 0 || i == n || j == n;
        return border ? 0.0 : a * std::sin(k * i) * std::sin(k * j) + jitter;
    });
}

post::SmoothParams flattening(double voxel, double maxMove, double flatMove)
{
    post::SmoothParams p;
    p.rounds = 6, p.maxMove = maxMove, p.flatten = true, p.flatMove = flatMove, p.voxel = voxel;
    return p;
}

/// RMS of z over the middle half of the sheet (away from the border it is held by)
double middleRms(const TriangleMesh& m)
{
    double sum = 0;
    size_t count = 0;
    for (const Vec3f& p : m.points)
        if (p.x >= 16 && p.x <= 48 && p.y >= 16 && p.y <= 48) sum += double(p.z) * p.z, ++count;
    return std::sqrt(sum / double(count));
}

TEST(Smooth, FlatteningTakesOutWideBumpsThatTaubinLeaves)
{
    const TriangleMesh bumpy = wavySheet(0.15);
    const TriangleMesh taubin = post::smoothAlongNormals(bumpy, 6, 0.2);
    const TriangleMesh flat = post::smoothAlongNormals(bumpy, flattening(1, 0.2, 0.4));
    // Taubin's pair keeps most of a bump 8 voxels wide; the flat steps take it out
    EXPECT_GT(middleRms(taubin), 0.6 * middleRms(bumpy));
    EXPECT_LT(middleRms(flat), 0.2 * middleRms(bumpy));
    for (size_t v = 0; v < bumpy.points.size(); ++v) {
        ASSERT_LE(length(flat.points[v] - bumpy.points[v]), 0.4 + 1e-6) << v;
        // along the normals of a nearly flat sheet: x and y stay
        EXPECT_NEAR(flat.points[v].x, bumpy.points[v].x, 0.05) << v;
        EXPECT_NEAR(flat.points[v].y, bumpy.points[v].y, 0.05) << v;
    }
    EXPECT_EQ(flat.triangles, bumpy.triangles);
    // without the flattening, or with no room for it, Taubin's rounds alone
    post::SmoothParams off = flattening(1, 0.2, 0.4);
    off.flatten = false;
    EXPECT_EQ(post::smoothAlongNormals(bumpy, off).points, taubin.points);
    EXPECT_EQ(post::smoothAlongNormals(bumpy, flattening(1, 0.2, 0)).points, taubin.points);
}

/// Two wavy sheets, the top one facing up at z = gap / 2, the bottom one facing down at
/// z = -gap / 2: the two sides of a sheet `gap` thick (open at their borders, which stay).
TriangleMesh twoSides(double gap)
{
    TriangleMesh top = wavySheet(0.15), m = top;
    const uint32_t n = uint32_t(top.points.size());
    for (Vec3f& p : m.points)
        p.z += float(gap / 2);
    for (const Vec3f& p : top.points)
        m.points.emplace_back(p.x, p.y, -p.z - float(gap / 2));
    for (const auto& t : top.triangles)
        m.triangles.push_back({t[0] + n, t[2] + n, t[1] + n});
    return m;
}

TEST(Smooth, FlatteningLeavesThinSheetsToTaubin)
{
    // 2 voxels thick: each side faces the other within the 3 voxels that make it thin
    const TriangleMesh thin = twoSides(2);
    EXPECT_EQ(post::smoothAlongNormals(thin, flattening(1, 0.2, 0.4)).points,
              post::smoothAlongNormals(thin, 6, 0.2).points);
    // 8 voxels thick: both sides flattened (each by itself as a sheet would be)
    const TriangleMesh thick = twoSides(8);
    const TriangleMesh flat = post::smoothAlongNormals(thick, flattening(1, 0.2, 0.4));
    const TriangleMesh one = post::smoothAlongNormals(wavySheet(0.15), flattening(1, 0.2, 0.4));
    for (size_t v = 0; v < one.points.size(); v += 97)
        EXPECT_NEAR(flat.points[v].z, one.points[v].z + 4, 1e-5) << v;
}

TEST(Smooth, FlatteningLeavesSmallCurvedBodiesToTaubin)
{
    // a sphere 10 voxels across (curvature 0.2 per voxel, past the 0.08 where the weight ends)
    const TriangleMesh bumpy = bumpySphere(0.02);
    const double voxel = 0.1;
    const TriangleMesh taubin = post::smoothAlongNormals(bumpy, 6, 0.2 * voxel);
    const TriangleMesh flat =
        post::smoothAlongNormals(bumpy, flattening(voxel, 0.2 * voxel, 0.4 * voxel));
    EXPECT_EQ(flat.points, taubin.points);
}

TEST(Smooth, FlatteningKeepsALargeBodysVolume)
{
    // a sphere 130 voxels across, its edges about a voxel long (level 6): flat at the weights'
    // scale, so the flat steps run on it, and plain Laplacian steps alone would shrink it (the
    // bound then caps the loss at 0.4 voxel, 1.8% of its volume)
    const TriangleMesh bumpy = bumpySphere(0.004, 6);
    const double voxel = 0.015;
    const post::SmoothParams p = flattening(voxel, 0.2 * voxel, 0.4 * voxel);
    const TriangleMesh flat = post::smoothAlongNormals(bumpy, p);
    const TriangleMesh taubin = post::smoothAlongNormals(bumpy, 6, 0.2 * voxel);
    EXPECT_LT(radiusSpread(flat), 0.7 * radiusSpread(taubin)); // 0.59x here
    const MeshReport before = checkMesh(bumpy), after = checkMesh(flat);
    EXPECT_TRUE(after.watertight()) << describe(after);
    EXPECT_NEAR(after.volume, before.volume, 0.003 * before.volume); // 1.00003 here
    for (size_t v = 0; v < flat.points.size(); ++v)
        ASSERT_LE(length(flat.points[v] - bumpy.points[v]), 0.4 * voxel + 1e-6) << v;
    std::printf("spread %.3g -> Taubin %.3g, flattened %.3g; volume %.5f\n", radiusSpread(bumpy),
                radiusSpread(taubin), radiusSpread(flat), after.volume / before.volume);
}

TEST(Smooth, SameBitsForAnyThreadCount)
{
    const TriangleMesh bumpy = bumpySphere(0.05);
    TriangleMesh one;
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = post::smoothAlongNormals(bumpy, 6, 0.03);
    }
    const TriangleMesh many = post::smoothAlongNormals(bumpy, 6, 0.03);
    EXPECT_EQ(one.points, many.points);
    const TriangleMesh sheet = wavySheet(0.15);
    const post::SmoothParams p = flattening(1, 0.2, 0.4);
    {
        tbb::global_control c(tbb::global_control::max_allowed_parallelism, 1);
        one = post::smoothAlongNormals(sheet, p);
    }
    EXPECT_EQ(one.points, post::smoothAlongNormals(sheet, p).points);
}

} // namespace
} // namespace fluidsurf
