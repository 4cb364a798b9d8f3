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

TEST(FlatWater, TheParticlesVolumeKeepsMoreCentresInside)
{
    // The line: non-isolated centres inside the default surface on 99.9%. Measured with
    // the particles' volume target (the default): 99.66% on double_dam_break (16 of 4,731 out),
    // 99.96-100% on the rest; with the raw mesh's volume 99.31-100%. What is held here: never
    // more outside than with the mesh's volume, and none lost (each within 0.75 r of the mesh:
    // measured 0.06-0.53 r, thin tips the surface just misses).
    FLUIDSURF_REQUIRE_SHARED_DATA();
    for (const test::RealFrame& f : test::kRealFrames) {
        if (!f.fluid) continue;
        SCOPED_TRACE(f.name);
        const ParticleSet ps = io::readParticles(test::sharedData() + "/real/" + f.name);
        size_t outside[2] = {0, 0};
        for (VolumeTarget v : {VolumeTarget::Mesh, VolumeTarget::Particles}) {
            ReconstructParams p = ReconstructParams::fromRadius(f.radius);
            p.post.volume = v;
            Context ctx;
            const ReconstructResult res = reconstruct(ps, p, ctx);
            const std::vector<Vec3f> kept = nonIsolated(ps, res);
            const std::vector<bool> inside = test::insideMesh(res.mesh, kept);
            for (size_t k = 0; k < kept.size(); ++k) {
                if (inside[k]) continue;
                ++outside[int(v)];
                double nearest = 1e300;
                for (const Vec3f& q : res.mesh.points) {
                    const double dx = q.x - kept[k].x, dy = q.y - kept[k].y, dz = q.z - kept[k].z;
                    nearest = std::min(nearest, dx * dx + dy * dy + dz * dz);
                }
                if (v == VolumeTarget::Particles)
                    EXPECT_LT(std::sqrt(nearest), 0.75 * f.radius) << "centre " << k;
            }
        }
        EXPECT_LE(outside[1], outside[0]);
        ::testing::Test::RecordProperty(std::string(f.name) + "_centres_outside_mesh_volume",
                                        std::to_string(outside[0]));
        ::testing::Test::RecordProperty(std::string(f.name) + "_centres_outside_particles_volume",
                                        std::to_string(outside[1]));
    }
}

} // namespace fluidsurf
