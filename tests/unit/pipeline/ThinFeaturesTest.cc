// Thin features (issue 64): sheets one and two particles thick and thin jets come out as one
// closed, manifold component (by default, and with ssp07-aniso and --smooth 20) with every particle
// centre inside the surface or within 0.25 r of it, judged by ray parity (MeshInside.h) and exact
// point-to-triangle distances.
#include "MeshInside.h"

#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/Scenes.h>

#include <gtest/gtest.h>

#include <string>

namespace fluidsurf {
namespace {

TriangleMesh unitCube()
{
    TriangleMesh m;
    for (int i = 0; i < 8; ++i)
        m.points.emplace_back(float(i & 1), float((i >> 1) & 1), float((i >> 2) & 1));
    m.triangles = {{0, 2, 1}, {1, 2, 3}, {4, 5, 6}, {5, 7, 6}, {0, 1, 4}, {1, 5, 4},
                   {2, 6, 3}, {3, 6, 7}, {0, 4, 2}, {2, 4, 6}, {1, 3, 5}, {3, 7, 5}};
    return m;
}

} // namespace

TEST(MeshInside, RayParityOfACube)
{
    const std::vector<Vec3f> points = {{0.3f, 0.6f, 0.2f},
                                       {0.3f, 0.6f, -0.2f},
                                       {0.3f, 0.6f, 1.2f},
                                       {1.3f, 0.6f, 0.5f},
                                       {0.91f, 0.07f, 0.93f}};
    const std::vector<bool> inside = test::insideMesh(unitCube(), points);
    EXPECT_EQ(inside, (std::vector<bool>{true, false, false, false, true}));
}

TEST(ThinFeatures, SheetsAndJetsAreOneClosedComponentAroundTheirParticles)
{
    struct Case
    {
        Scene scene;
        int layers;
        double jitter;
    };
    const Case cases[] = {
        {Scene::Sheet, 1, 0.2}, {Scene::Sheet, 2, 0.2}, {Scene::Jet, 1, 0.1}, {Scene::Jet, 2, 0.2}};
    for (const Case& c : cases)
        for (const bool flat : {false, true}) { // the default; the flat-water settings
            SceneParams sp;
            sp.count = 6000, sp.radius = 0.025, sp.layers = c.layers, sp.jitter = c.jitter;
            const ParticleSet ps = generateScene(c.scene, sp);
            const std::string what = std::string(sceneName(c.scene)) + " of " +
                                     std::to_string(c.layers) + " layers" +
                                     (flat ? ", ssp07-aniso --smooth 20" : "");
            ReconstructParams p = ReconstructParams::fromRadius(sp.radius);
            if (flat) p.field.field = FieldKind::Ssp07Aniso, p.post.smooth = 20;
            Context ctx;
            const ReconstructResult res = reconstruct(ps, p, ctx);
            const MeshReport report = checkMesh(res.mesh);
            EXPECT_TRUE(report.watertight()) << what << ": " << describe(report);
            EXPECT_EQ(res.isolatedParticles.size(), 0u) << what;
            EXPECT_EQ(report.components, 1u) << what;
            // the centres outside the surface: each within 0.25 r of it
            const std::vector<bool> inside = test::insideMesh(res.mesh, ps.positions);
            TriangleMesh outside;
            for (size_t i = 0; i < ps.size(); ++i)
                if (!inside[i]) outside.points.push_back(ps.positions[i]);
            EXPECT_LE(meshDistance(outside, res.mesh, sp.radius), 0.25 * sp.radius)
                << what << ": " << outside.points.size() << " of " << ps.size()
                << " centres outside the surface";
        }
}

} // namespace fluidsurf
