// The written level set: OpenVDB conventions (class, name, transform, background, signs) and
// the metadata, read back through OpenVDB.
#include "TestData.h"

#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Scenes.h>
#include <fluidsurf/io/LevelSetIO.h>

#include <openvdb/openvdb.h>

#include <limits>

using namespace fluidsurf;
using namespace fluidsurf::test;

TEST(LevelSet, FileIsAnOpenVdbLevelSetWithMetadata)
{
    SceneParams sp;
    sp.count = 12 * 12 * 12;
    const ParticleSet ps = generateScene(Scene::Block, sp);
    Params p = Params::fromRadius(sp.radius);
    p.voxelSize = 0.5 * sp.radius;
    const RasterizeResult res = rasterizeParticles(ps, p, "block.bgeo");
    TempDir dir;
    io::writeLevelSet({res.grid}, dir.path("block.vdb"));

    openvdb::io::File file(dir.path("block.vdb"));
    file.open();
    const openvdb::GridBase::Ptr base = file.readGrid("surface");
    file.close();
    const auto grid = openvdb::gridPtrCast<openvdb::FloatGrid>(base);
    ASSERT_TRUE(grid);
    EXPECT_EQ(grid->getGridClass(), openvdb::GRID_LEVEL_SET);
    EXPECT_DOUBLE_EQ(grid->voxelSize()[0], p.voxelSize);
    EXPECT_EQ(grid->indexToWorld(openvdb::Coord(4, -2, 8)), openvdb::Vec3d(4, -2, 8) * p.voxelSize);
    EXPECT_FLOAT_EQ(grid->background(), float(3 * p.voxelSize));
    EXPECT_EQ(grid->activeVoxelCount(), res.grid->activeVoxelCount());
    for (const std::string& name : levelSetMetadataNames())
        EXPECT_TRUE((*grid)[name]) << name;
    EXPECT_EQ(grid->metaValue<double>("fluidsurf:particle_radius"), sp.radius);
    EXPECT_EQ(grid->metaValue<double>("fluidsurf:influence_radius"), 4 * sp.radius);
    EXPECT_EQ(grid->metaValue<std::string>("fluidsurf:field"), "ssp07");
    EXPECT_EQ(grid->metaValue<std::string>("fluidsurf:method"), "narrow-band");
    EXPECT_EQ(grid->metaValue<int64_t>("fluidsurf:particle_count"), int64_t(ps.size()));
    EXPECT_EQ(grid->metaValue<std::string>("fluidsurf:source"), "block.bgeo");

    // Signs: the block's centre is deep inside (flood-filled), a point beyond it outside;
    // every active value lies within the background.
    const double centre = 5.5 * 2 * sp.radius / p.voxelSize;
    const auto acc = grid->getConstAccessor();
    const int mid = int(centre);
    const openvdb::Coord inside{mid, mid, mid};
    EXPECT_FALSE(acc.isValueOn(inside));
    EXPECT_FLOAT_EQ(acc.getValue(inside), -grid->background());
    EXPECT_FLOAT_EQ(acc.getValue(openvdb::Coord{3 * mid, mid, mid}), grid->background());
    for (auto it = grid->cbeginValueOn(); it; ++it)
        ASSERT_LE(std::abs(*it), grid->background());
}

TEST(LevelSet, WriteFailureLeavesNothing)
{
    SceneParams sp;
    sp.count = 1000;
    const RasterizeResult res =
        rasterizeParticles(generateScene(Scene::Block, sp), Params::fromRadius(sp.radius));
    EXPECT_THROW(io::writeLevelSet({res.grid}, "/nonexistent-folder/x.vdb"), OutputError);
}

TEST(LevelSet, NonFinitePositionsAreRejectedByTheFirstOne)
{
    // 400,000 particles (several ranges of the parallel check), two of them not finite: the
    // error names the lower index, wherever the threads found them first.
    ParticleSet ps;
    for (int i = 0; i < 400000; ++i)
        ps.positions.emplace_back(0.01f * float(i % 100), 0.01f * float(i / 100 % 100),
                                  0.01f * float(i / 10000));
    ps.positions[312345].z = std::numeric_limits<float>::infinity();
    ps.positions[270001].y = std::numeric_limits<float>::quiet_NaN();
    for (int threads : {1, 4}) {
        Context ctx;
        ctx.setThreads(threads);
        try {
            rasterizeParticles(ps, Params::fromRadius(0.005), ctx);
            ADD_FAILURE() << "no error";
        } catch (const ValueError& e) {
            EXPECT_NE(std::string(e.what()).find("particle 270001 has a non-finite position"),
                      std::string::npos)
                << e.what();
        }
    }
}

TEST(LevelSet, InvalidParametersAreRejected)
{
    SceneParams sp;
    sp.count = 100;
    const ParticleSet ps = generateScene(Scene::Block, sp);
    Params p = Params::fromRadius(sp.radius);
    p.tLow = 4;
    EXPECT_THROW(rasterizeParticles(ps, p), ValueError);
    p = Params::fromRadius(sp.radius);
    p.voxelSize = 0;
    EXPECT_THROW(rasterizeParticles(ps, p), ValueError);
    p = Params::fromRadius(sp.radius);
    p.voxelSize = sp.radius / 32, p.influenceRadius = 1001 * p.voxelSize; // a huge kernel
    EXPECT_THROW(rasterizeParticles(ps, p), ValueError);
    for (double Params::*length : {&Params::smoothingLength, &Params::bandWidth}) {
        p = Params::fromRadius(sp.radius);
        p.*length = 1001 * p.voxelSize; // each length in voxels is bounded, with the range named
        try {
            rasterizeParticles(ps, p);
            ADD_FAILURE() << "no error";
        } catch (const ValueError& e) {
            EXPECT_NE(std::string(e.what()).find("the range is (0, 1000] voxels"),
                      std::string::npos)
                << e.what();
        }
        p.*length = 1000 * p.voxelSize; // the end of the range is allowed
        EXPECT_NO_THROW(p.validate());
    }
    p = Params::fromRadius(sp.radius);
    p.halfWidth = 1001;
    EXPECT_THROW(rasterizeParticles(ps, p), ValueError);
    // One stray particle beyond the grid's reach is isolated (ReconstructTest); a far cluster,
    // which is fluid, cannot be gridded with the rest and says so.
    ParticleSet far;
    far.positions = ps.positions;
    far.positions.push_back(Vec3f(1e12f, 0, 0)); // 2^21 cells cannot span it
    EXPECT_EQ(rasterizeParticles(far, Params::fromRadius(sp.radius)).isolatedParticles.back(),
              uint32_t(ps.size()));
    far.positions.push_back(Vec3f(1e12f, 0, 0)); // a pair: not isolated
    try {
        rasterizeParticles(far, Params::fromRadius(sp.radius));
        ADD_FAILURE() << "no error";
    } catch (const ValueError& e) {
        EXPECT_NE(std::string(e.what()).find("stray particle"), std::string::npos) << e.what();
    }
}
