// ActiveTilesTest.cc - level sets stored with active tiles (issue 63): meshed as the surface of
// their voxelized form, closed, at a cost in the tiles' faces, by both meshers; refused past the
// memory budget with the estimate.
#include <fluidsurf/Context.h>
#include <fluidsurf/Error.h>
#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/MeshLevelSet.h>

#include "mesh/MarchingCubes.h"

#include <gtest/gtest.h>
#include <openvdb/openvdb.h>
#include <openvdb/tools/LevelSetSphere.h>

#include <cmath>
#include <string>

namespace fluidsurf {
namespace {

using openvdb::Coord;
using openvdb::CoordBBox;

/// A box of active tiles (and the leaves fill() makes where the box is not tile-aligned) at
/// -3 in a background of +3, voxel 1: the level set other tools write after pruning.
openvdb::FloatGrid::Ptr tiledBox(const CoordBBox& box)
{
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(3.0f);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    grid->tree().fill(box, -3.0f, /*active=*/true);
    return grid;
}

/// The same grid with every active tile made active voxels.
openvdb::FloatGrid::Ptr voxelized(const openvdb::FloatGrid& grid)
{
    openvdb::FloatGrid::Ptr copy = grid.deepCopy();
    copy->tree().voxelizeActiveTiles();
    return copy;
}

/// Marching cubes' surface of a voxelized box of X x Y x Z voxels at -3 in +3: the box grown
/// by half a voxel, whose edges are cut by a 45-degree chamfer of half a voxel (a cell with two
/// inside corners of four across the edge) and whose corners lose a little more. Volume:
/// XYZ - (X + Y + Z) / 2 + 2/3 (the eight corners, 1/12 each); area: 2(XY + YZ + ZX) less
/// (1 - sqrt(1/2)) per unit of the twelve edges' length.
double boxVolume(double x, double y, double z)
{
    return x * y * z - (x + y + z) / 2 + 2.0 / 3;
}
double boxArea(double x, double y, double z)
{
    return 2 * (x * y + y * z + z * x) - 4 * (x + y + z) * (1 - std::sqrt(0.5));
}

// A 512^3 box of tiles meshed to nothing: its cells across the faces met inactive background.
// Its surface lies halfway between -3 and +3, half a voxel outside the box's voxels.
TEST(ActiveTiles, ATiledBoxIsTheClosedBox)
{
    const auto grid = tiledBox(CoordBBox(Coord(0), Coord(511)));
    ASSERT_TRUE(grid->tree().hasActiveTiles());
    ASSERT_EQ(grid->tree().leafCount(), 0u);
    const TriangleMesh mesh = meshLevelSet(*grid, Mesher::MarchingCubes);
    const MeshReport r = checkMesh(mesh);
    EXPECT_TRUE(r.watertight()) << describe(r);
    EXPECT_EQ(r.components, 1u);
    EXPECT_NEAR(r.volume, boxVolume(512, 512, 512), 0.01);
    EXPECT_NEAR(r.area, boxArea(512, 512, 512), 1.0); // (corners not counted: about 0.7)
    for (const Vec3f& p : mesh.points)
        for (int a = 0; a < 3; ++a)
            ASSERT_TRUE(p[a] >= -0.5f && p[a] <= 511.5f) << p[a];
    // the work is the faces': at most the leaves on both sides of them, grown by a voxel, not
    // the 262,144 leaves of the voxelized box
    Context ctx;
    openvdb::FloatTree::Ptr keep;
    mesh::leafOnlyTree(*grid, keep, ctx);
    ASSERT_TRUE(keep);
    EXPECT_LE(keep->leafCount(), 6u * 64 * 64 * 2 + 12u * 64 * 4 + 8u * 8);
    EXPECT_FALSE(keep->hasActiveTiles());
}

// OpenVDB's mesher on the same tiled box went past 8 GB on some layouts: it gets the same tree.
TEST(ActiveTiles, OpenVdbsMesherGetsTheSameTree)
{
    const auto grid = tiledBox(CoordBBox(Coord(0), Coord(255)));
    const MeshReport r = checkMesh(meshLevelSet(*grid, Mesher::OpenVdb));
    EXPECT_NEAR(r.volume / (256.0 * 256 * 256), 1, 0.01) << describe(r);
    EXPECT_NEAR(r.area / (6.0 * 256 * 256), 1, 0.01) << describe(r);
}

/// Both meshes have the same triangles at the same places (numbering aside): volume, area and
/// the distance each way.
void expectSameSurface(const TriangleMesh& a, const TriangleMesh& b, const std::string& what)
{
    const MeshReport ra = checkMesh(a), rb = checkMesh(b);
    EXPECT_TRUE(ra.watertight()) << what << ": " << describe(ra);
    EXPECT_EQ(ra.triangles, rb.triangles) << what;
    EXPECT_NEAR(ra.volume, rb.volume, 1e-9 * std::abs(rb.volume)) << what;
    EXPECT_NEAR(ra.area, rb.area, 1e-9 * rb.area) << what;
    EXPECT_LE(meshDistance(a, b, 2.0), 1e-5) << what;
    EXPECT_LE(meshDistance(b, a, 2.0), 1e-5) << what;
}

// A box of 8^3 tiles, not aligned to the larger tiles, with a tile-sized pocket of the other
// sign inside it (a second surface, facing in). Both are closed, at the voxelized grid's
// surface, as OpenVDB's mesher of the voxelized grid has it.
TEST(ActiveTiles, ABoxWithAPocketIsItsVoxelizedSurface)
{
    auto grid = tiledBox(CoordBBox(Coord(-40, 8, 16), Coord(183, 143, 303)));
    grid->tree().addTile(1, Coord(64, 64, 128), 3.0f, true); // an 8^3 pocket of outside
    ASSERT_TRUE(grid->tree().hasActiveTiles());
    ASSERT_EQ(grid->tree().leafCount(), 0u);
    const TriangleMesh mesh = meshLevelSet(*grid, Mesher::MarchingCubes);
    const MeshReport r = checkMesh(mesh);
    EXPECT_TRUE(r.watertight()) << describe(r);
    EXPECT_EQ(r.components, 2u);
    // the pocket's surface is the box formula's, facing in
    EXPECT_NEAR(r.volume, boxVolume(224, 136, 288) - boxVolume(8, 8, 8), 0.01);
    EXPECT_NEAR(r.area, boxArea(224, 136, 288) + boxArea(8, 8, 8), 2.0);
    const MeshReport o = checkMesh(meshLevelSet(*voxelized(*grid), Mesher::OpenVdb));
    EXPECT_NEAR(r.volume / o.volume, 1, 0.01) << describe(o);
    EXPECT_NEAR(r.area / o.area, 1, 0.01) << describe(o);
}

// A coarse band: 8^3 tiles whose values are the distance from a sphere at their centres, both
// signs, all active, with inactive tiles inside and the background outside. Every crossing
// lies between active values, so the voxelized grid meshes it whole with our mesher: the same
// surface, triangle for triangle.
TEST(ActiveTiles, ACoarseBandOfTilesIsTheVoxelizedGridsMesh)
{
    openvdb::initialize();
    auto grid = openvdb::FloatGrid::create(24.0f);
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    const double radius = 61.3;
    for (int x = -96; x < 96; x += 8)
        for (int y = -96; y < 96; y += 8)
            for (int z = -96; z < 96; z += 8) {
                const double d =
                    std::sqrt(std::pow(x + 3.5, 2) + std::pow(y + 3.5, 2) + std::pow(z + 3.5, 2)) -
                    radius;
                if (std::abs(d) < 20)
                    grid->tree().addTile(1, Coord(x, y, z), float(d), true);
                else if (d < 0)
                    grid->tree().addTile(1, Coord(x, y, z), -24.0f, false);
            }
    ASSERT_TRUE(grid->tree().hasActiveTiles());
    const TriangleMesh tiled = meshLevelSet(*grid, Mesher::MarchingCubes);
    ASSERT_FALSE(tiled.empty());
    expectSameSurface(tiled, meshLevelSet(*voxelized(*grid), Mesher::MarchingCubes), "coarse band");
}

// A level set pruned the usual way, its inside then left as active tiles: the band's mesh,
// unchanged by the tiles behind it.
TEST(ActiveTiles, ActiveInsideTilesBehindABandChangeNothing)
{
    openvdb::initialize();
    auto grid =
        openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(40.0f, openvdb::Vec3f(1.3f), 1.0f);
    const TriangleMesh plain = meshLevelSet(*grid, Mesher::MarchingCubes);
    openvdb::FloatTree::ValueOffIter tile = grid->tree().beginValueOff();
    tile.setMaxDepth(openvdb::FloatTree::ValueOffIter::LEAF_DEPTH - 1);
    size_t activated = 0;
    for (; tile; ++tile)
        if (*tile < 0) tile.setActiveState(true), ++activated;
    ASSERT_GT(activated, 0u);
    ASSERT_TRUE(grid->tree().hasActiveTiles());
    const TriangleMesh tiled = meshLevelSet(*grid, Mesher::MarchingCubes);
    EXPECT_TRUE(tiled.points == plain.points);
    EXPECT_TRUE(tiled.triangles == plain.triangles);
}

// Past the memory budget: refused before the leaves are made, with the estimate.
TEST(ActiveTiles, RefusedPastTheMemoryBudgetWithTheEstimate)
{
    const auto grid = tiledBox(CoordBBox(Coord(0), Coord(1023)));
    Context ctx;
    ctx.setMemoryBudget(8 << 20);
    try {
        meshLevelSet(*grid, Mesher::MarchingCubes, ctx);
        FAIL() << "no error";
    } catch (const ValueError& e) {
        const std::string what = e.what();
        EXPECT_NE(what.find("active tiles"), std::string::npos) << what;
        EXPECT_NE(what.find("needs about"), std::string::npos) << what;
        EXPECT_NE(what.find("memory budget of 8 MiB"), std::string::npos) << what;
    }
}

} // namespace
} // namespace fluidsurf
