// MeshCudaTest.cc - marching cubes on the GPU against the CPU's: the same bytes (positions,
// normals, triangles, cell counts) on level sets of our own and of other tools, at two voxel
// sizes, with a rotated and shifted transform, with an active tile, without normals; and the CPU
// taking over where the band lies beyond the GPU's leaf keys.
#include "../field/RequireGpu.h"
#include "TestData.h"

#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/MeshLevelSet.h>
#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Scenes.h>
#include <fluidsurf/io/ParticleIO.h>

#include <openvdb/tools/LevelSetSphere.h>

#include <gtest/gtest.h>

#include <cstring>

namespace fluidsurf {
namespace {

/// The GPU's mesh of grid is the CPU's, byte for byte; onGpu: whether the GPU took it.
void expectSameMeshOnGpu(const openvdb::FloatGrid& grid, const std::string& what,
                         RawNormals normals = RawNormals::Gradient, bool onGpu = true)
{
    SCOPED_TRACE(what);
    Context cpu, gpu(Device::Cuda);
    MeshStats cs, gs;
    const TriangleMesh a = meshLevelSet(grid, Mesher::MarchingCubes, cpu, &cs, normals);
    const TriangleMesh b = meshLevelSet(grid, Mesher::MarchingCubes, gpu, &gs, normals);
    EXPECT_EQ(cs.device, "cpu");
    if (onGpu)
        EXPECT_NE(gs.device.substr(0, 3), "cpu") << gs.device;
    else
        EXPECT_EQ(gs.device, "cpu (the band lies beyond the GPU's leaf keys)");
    EXPECT_EQ(cs.surfaceCells, gs.surfaceCells);
    ASSERT_EQ(a.points.size(), b.points.size());
    ASSERT_EQ(a.normals.size(), b.normals.size());
    ASSERT_EQ(a.triangles.size(), b.triangles.size());
    EXPECT_EQ(0, std::memcmp(a.points.data(), b.points.data(), a.points.size() * sizeof(Vec3f)));
    EXPECT_EQ(0, std::memcmp(a.normals.data(), b.normals.data(), a.normals.size() * sizeof(Vec3f)));
    EXPECT_TRUE(a.triangles == b.triangles);
    // (float positions 2^24 voxels out cannot make a clean mesh: the far case is not checked)
    if (onGpu && !b.empty()) EXPECT_TRUE(checkMesh(b).watertight()) << describe(checkMesh(b));
}

TEST(MarchingCubesCuda, SameBytesOnGeneratedScenes)
{
    FLUIDSURF_REQUIRE_GPU();
    for (Scene scene : {Scene::Drop, Scene::Ball, Scene::Block}) {
        SceneParams sp;
        sp.count = 20000;
        Params p = Params::fromRadius(sp.radius);
        const RasterizeResult fine = rasterizeParticles(generateScene(scene, sp), p);
        expectSameMeshOnGpu(*fine.grid, sceneName(scene));
        // coarse voxels: many cells with an ambiguous face (centre vertices)
        p.voxelSize = 2 * sp.radius;
        const RasterizeResult coarse = rasterizeParticles(generateScene(scene, sp), p);
        expectSameMeshOnGpu(*coarse.grid, std::string(sceneName(scene)) + "_voxel2r");
        expectSameMeshOnGpu(*coarse.grid, std::string(sceneName(scene)) + "_no_normals",
                            RawNormals::None);
    }
}

TEST(MarchingCubesCuda, SameBytesOnRealFrames)
{
    FLUIDSURF_REQUIRE_GPU();
    FLUIDSURF_REQUIRE_SHARED_DATA();
    for (const test::RealFrame& f : test::kRealFrames) {
        const ParticleSet ps = io::readParticles(test::sharedData() + "/real/" + f.name);
        const RasterizeResult res = rasterizeParticles(ps, Params::fromRadius(f.radius));
        expectSameMeshOnGpu(*res.grid, f.name);
    }
}

TEST(MarchingCubesCuda, SameBytesOnOtherToolsGrids)
{
    FLUIDSURF_REQUIRE_GPU();
    openvdb::initialize();
    auto sphere = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        1.3f, openvdb::Vec3f(0.2f, -0.1f, 0.05f), 0.1f);
    expectSameMeshOnGpu(*sphere, "openvdb_sphere");
    // rotated, scaled unevenly and shifted: positions and normals through the full affine map
    openvdb::math::Mat4d m = openvdb::math::Mat4d::identity();
    m.preRotate(openvdb::math::Z_AXIS, 0.4);
    m.preRotate(openvdb::math::X_AXIS, -0.25);
    m.preScale(openvdb::Vec3d(0.1, 0.13, 0.08));
    m.postTranslate(openvdb::Vec3d(3.5, -2.25, 100.125));
    openvdb::FloatGrid::Ptr skewed = sphere->deepCopy();
    skewed->setTransform(openvdb::math::Transform::createLinearTransform(m));
    expectSameMeshOnGpu(*skewed, "openvdb_sphere_affine");
    // an active tile (both meshers make its voxels leaves first)
    openvdb::FloatGrid::Ptr tiled = sphere->deepCopy();
    tiled->tree().addTile(1, openvdb::Coord(256, 0, 0), -0.05f, true);
    expectSameMeshOnGpu(*tiled, "openvdb_sphere_with_an_active_tile");
    const openvdb::FloatGrid::Ptr empty = openvdb::FloatGrid::create(0.3f);
    expectSameMeshOnGpu(*empty, "empty");
}

TEST(MarchingCubesCuda, TheCpuTakesBandsBeyondTheLeafKeys)
{
    FLUIDSURF_REQUIRE_GPU();
    openvdb::initialize();
    // two balls 2^24 voxels apart: more leaves across than the GPU's 21-bit keys hold
    auto grid =
        openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(0.5f, openvdb::Vec3f(0.f), 0.1f);
    auto far = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        0.5f, openvdb::Vec3f(0.1f * float(1 << 24), 0.f, 0.f), 0.1f);
    grid->tree().merge(far->tree());
    expectSameMeshOnGpu(*grid, "far_apart", RawNormals::Gradient, false);
}

} // namespace
} // namespace fluidsurf
