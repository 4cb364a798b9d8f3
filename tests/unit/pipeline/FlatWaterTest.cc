// Flat water (issue 64): ssp07-aniso with 20 rounds of smoothing, the combination that is
// flatter than splashsurf 0.14 (BENCHMARKS.md), on every real fluid frame: closed and manifold,
// no more components than the raw SSP07 mesh (no new blobs). Its distance to that mesh and the
// particles it leaves outside (ray parity, MeshInside.h) are recorded, not held to the issue's
// 1 r and 99.9%: it misses both (1.7-2.2 r on four frames, where the stretched kernels carry it
// into sparse regions and narrow gaps, 2.1-2.9 r from the nearest particle; up to 2.9% of the
// centres outside, where 0.1-0.7% already lie outside today's default), which is why it is not
// the default. Thin sheets and jets: ThinFeaturesTest, for it and for the default.
#include "MeshInside.h"
#include "TestData.h"

#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/io/ParticleIO.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>

namespace fluidsurf {
namespace {

ReconstructParams flatWater(double r)
{
    ReconstructParams p = ReconstructParams::fromRadius(r);
    p.field.field = FieldKind::Ssp07Aniso;
    p.post.smooth = 20;
    return p;
}

ReconstructParams rawSsp07(double r)
{
    ReconstructParams p = ReconstructParams::fromRadius(r);
    p.post.decimate = 0, p.post.smooth = 0, p.post.subdivide = 0;
    return p;
}

/// The centres of the particles that res did not find isolated (the field's particles).
std::vector<Vec3f> nonIsolated(const ParticleSet& ps, const ReconstructResult& res)
{
    std::vector<uint32_t> isolated = res.isolatedParticles;
    std::sort(isolated.begin(), isolated.end());
    std::vector<Vec3f> kept;
    for (uint32_t i = 0; i < ps.size(); ++i)
        if (!std::binary_search(isolated.begin(), isolated.end(), i))
            kept.push_back(ps.positions[i]);
    return kept;
}

} // namespace

TEST(FlatWater, RealFramesAreClosedWithNoNewBlobs)
{
    FLUIDSURF_REQUIRE_SHARED_DATA();
    for (const test::RealFrame& f : test::kRealFrames) {
        if (!f.fluid) continue;
        SCOPED_TRACE(f.name);
        const ParticleSet ps = io::readParticles(test::sharedData() + "/real/" + f.name);
        Context ctx;
        const ReconstructResult flat = reconstruct(ps, flatWater(f.radius), ctx);
        const ReconstructResult raw = reconstruct(ps, rawSsp07(f.radius), ctx);
        const MeshReport report = checkMesh(flat.mesh), rawReport = checkMesh(raw.mesh);
        EXPECT_TRUE(report.watertight()) << describe(report);
        EXPECT_LE(report.components - flat.isolatedSpheres,
                  rawReport.components - raw.isolatedSpheres);
        const double distance = meshDistance(flat.mesh, raw.mesh, 4 * f.radius) / f.radius;
        const std::vector<Vec3f> kept = nonIsolated(ps, flat);
        const std::vector<bool> inside = test::insideMesh(flat.mesh, kept);
        const size_t in = size_t(std::count(inside.begin(), inside.end(), true));
        ::testing::Test::RecordProperty(std::string(f.name) + "_distance_to_raw_ssp07_in_r",
                                        std::to_string(distance));
        ::testing::Test::RecordProperty(std::string(f.name) + "_centres_outside",
                                        std::to_string(kept.size() - in));
    }
}

} // namespace fluidsurf

namespace fluidsurf {

TEST(FlatWater, TheDefaultSurfaceHoldsTheCentres)
{
    // The detail line on every real fluid frame: non-isolated centres inside the default
    // surface on at least 99.9% (ray parity; measured 100% with the covering, 99.66-100% without
    // it, 99.31-100% with the raw mesh's volume), within 1 r of today's raw SSP07 mesh (measured
    // at most 0.79 r). Covering leaves no more outside than either, and the mesh closed.
    FLUIDSURF_REQUIRE_SHARED_DATA();
    for (const test::RealFrame& f : test::kRealFrames) {
        if (!f.fluid) continue;
        SCOPED_TRACE(f.name);
        const ParticleSet ps = io::readParticles(test::sharedData() + "/real/" + f.name);
        Context ctx;
        const ReconstructResult raw = reconstruct(ps, rawSsp07(f.radius), ctx);
        size_t outside[3] = {0, 0, 0}, kept = 0;
        for (int run = 0; run < 3; ++run) {
            ReconstructParams p = ReconstructParams::fromRadius(f.radius);
            if (run == 1) p.post.cover = false;
            if (run == 2) p.post.cover = false, p.post.volume = VolumeTarget::Mesh;
            const ReconstructResult res = reconstruct(ps, p, ctx);
            const std::vector<Vec3f> centres = nonIsolated(ps, res);
            const std::vector<bool> inside = test::insideMesh(res.mesh, centres);
            outside[run] = size_t(std::count(inside.begin(), inside.end(), false));
            if (run > 0) continue;
            kept = centres.size();
            const MeshReport report = checkMesh(res.mesh);
            EXPECT_TRUE(report.watertight()) << describe(report);
            EXPECT_LE(meshDistance(res.mesh, raw.mesh, 4 * f.radius), f.radius);
        }
        EXPECT_LE(double(outside[0]), 0.001 * double(kept)) << outside[0] << " of " << kept;
        EXPECT_LE(outside[0], outside[1]);
        EXPECT_LE(outside[0], outside[2]);
        ::testing::Test::RecordProperty(std::string(f.name) + "_centres_outside",
                                        std::to_string(outside[0]));
        ::testing::Test::RecordProperty(std::string(f.name) + "_centres_outside_uncovered",
                                        std::to_string(outside[1]));
    }
}

} // namespace fluidsurf
