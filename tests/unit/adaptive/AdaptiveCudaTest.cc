// AdaptiveCudaTest.cc - the 3-level grid with the field on the GPU: the same level map and the
// same mesh as on the CPU, to the bit where the CPU sums the field on 8 lanes as the GPU does
// (else values within 1e-5 r). Skipped where there is no usable GPU.
#include "field/GatherField.h"
#include "unit/field/RequireGpu.h"

#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/Scenes.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>

namespace fluidsurf {
namespace {

TEST(AdaptiveCuda, TheGpuGivesTheCpusLevelMapAndMesh)
{
    FLUIDSURF_REQUIRE_GPU();
    for (Scene scene : {Scene::Drop, Scene::Slab, Scene::Ball}) {
        SceneParams sp;
        sp.count = 100000;
        const ParticleSet ps = generateScene(scene, sp);
        ReconstructParams p = ReconstructParams::fromRadius(sp.radius);
        p.field.adaptive = true;
        p.post.isolated = IsolatedMode::Drop;
        p.post.decimate = 0, p.post.smooth = 0, p.post.subdivide = 0;
        Context cpu, gpu;
        gpu.setDevice(Device::Cuda);
        const ReconstructResult a = reconstruct(ps, p, cpu, "cpu");
        const ReconstructResult b = reconstruct(ps, p, gpu, "gpu");
        SCOPED_TRACE(sceneName(scene));
        EXPECT_NE(b.field.device, "cpu");
        const auto& la = a.adaptiveGrid.levels->tree();
        const auto& lb = b.adaptiveGrid.levels->tree();
        EXPECT_TRUE(la.hasSameTopology(lb));
        auto acc = b.adaptiveGrid.levels->getConstAccessor();
        size_t differ = 0;
        for (auto v = la.cbeginValueOn(); v; ++v)
            differ += acc.getValue(v.getCoord()) != *v;
        EXPECT_EQ(differ, 0u);
        EXPECT_TRUE(checkMesh(b.mesh).watertight());
        EXPECT_EQ(a.adaptiveMesh.mergedCrackPoints, b.adaptiveMesh.mergedCrackPoints);
        EXPECT_EQ(a.adaptiveMesh.patchTriangles, b.adaptiveMesh.patchTriangles);
        ASSERT_EQ(a.mesh.points.size(), b.mesh.points.size());
        ASSERT_EQ(a.mesh.triangles.size(), b.mesh.triangles.size());
        size_t first = 0;
        while (first < a.mesh.triangles.size() &&
               a.mesh.triangles[first] == b.mesh.triangles[first])
            ++first;
        ASSERT_EQ(first, a.mesh.triangles.size()) << "the first triangle that differs";
        // Values agree within 1e-5 r, which moves a crossing by about as much; the points are
        // floats, whose rounding at |x| ~ 1 adds a few more units of 1e-7 (4 ulps allowed).
        double worst = 0;
        for (size_t i = 0; i < a.mesh.points.size(); ++i) {
            const Vec3f &x = a.mesh.points[i], &y = b.mesh.points[i];
            for (int k = 0; k < 3; ++k) {
                const float u = k == 0   ? x.x
                                : k == 1 ? x.y
                                         : x.z,
                            w = k == 0   ? y.x
                                : k == 1 ? y.y
                                         : y.z;
                const double ulp = std::nextafter(std::abs(u), 1e30f) - std::abs(u);
                worst = std::max(worst, double(std::abs(u - w)));
                ASSERT_LE(std::abs(u - w), 1e-5 * sp.radius + 4 * ulp) << i;
            }
        }
        if (field::fieldLanes() == 8) // the CPU's sums (GatherField.h): the same points
            EXPECT_EQ(0, std::memcmp(a.mesh.points.data(), b.mesh.points.data(),
                                     a.mesh.points.size() * sizeof(Vec3f)));
        RecordProperty("worst_point_difference_r", std::to_string(worst / sp.radius));
        std::printf("%s: points within %.3g r of the CPU's\n", sceneName(scene), worst / sp.radius);
    }
}

} // namespace
} // namespace fluidsurf
