// The narrow band against the volume baselines (gather-full, scatter), and determinism.
#include "TestData.h"

#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Scenes.h>
#include <fluidsurf/io/LevelSetIO.h>

#include <tbb/global_control.h>

using namespace fluidsurf;
using namespace fluidsurf::test;

namespace {

ParticleSet testFrame(const std::string& name)
{
    if (!sharedData().empty()) return io::readParticles(sharedData() + "/real/" + name);
    SceneParams sp;
    sp.count = 5000;
    return generateScene(Scene::Drop, sp);
}

RasterizeResult run(const ParticleSet& ps, FieldMethod method, double r = 0.025)
{
    Params p = Params::fromRadius(r);
    p.method = method;
    return rasterizeParticles(ps, p);
}

/// Every sign change between axis neighbours of the full grid lies between two narrow-band
/// voxels with the same signs: the same zero crossings, and none elsewhere (no double layer).
void expectSameZeroCrossings(const openvdb::FloatGrid& band, const openvdb::FloatGrid& full,
                             const std::string& what)
{
    auto b = band.getConstAccessor();
    auto f = full.getConstAccessor();
    size_t crossings = 0, missing = 0;
    for (auto it = full.cbeginValueOn(); it; ++it) {
        const openvdb::Coord c = it.getCoord();
        for (int axis = 0; axis < 3; ++axis) {
            openvdb::Coord n = c;
            n[axis] += 1;
            const float v0 = *it, v1 = f.getValue(n);
            if ((v0 < 0) == (v1 < 0)) continue;
            ++crossings;
            const bool ok = b.isValueOn(c) && b.isValueOn(n) && (b.getValue(c) < 0) == (v0 < 0) &&
                            (b.getValue(n) < 0) == (v1 < 0);
            if (!ok && missing++ < 5)
                ADD_FAILURE() << what << ": crossing " << c << " -> " << n << " not in the band";
        }
    }
    EXPECT_EQ(missing, 0u) << what;
    EXPECT_GT(crossings, 100u) << what;
}

} // namespace

TEST(Methods, NarrowBandEqualsGatherFullOnItsVoxels)
{
    for (const char* name : {"dam_break_frame_9_6859_particles.bgeo",
                             "double_dam_break_frame_26_4732_particles.vtk"}) {
        const ParticleSet ps = testFrame(name);
        const RasterizeResult band = run(ps, FieldMethod::NarrowBand),
                              full = run(ps, FieldMethod::GatherFull);
        auto f = full.grid->getConstAccessor();
        size_t differ = 0;
        for (auto it = band.grid->cbeginValueOn(); it; ++it)
            if (*it != f.getValue(it.getCoord()) && differ++ < 5)
                ADD_FAILURE() << name << ": " << it.getCoord() << " band " << *it << " full "
                              << f.getValue(it.getCoord());
        EXPECT_EQ(differ, 0u) << "values must be bitwise identical";
        expectSameZeroCrossings(*band.grid, *full.grid, name);
        EXPECT_LT(band.stats.fieldEvaluations * 3, full.stats.fieldEvaluations)
            << "the band is a fraction of the volume";
    }
}

TEST(Methods, ScatterMatchesGatherFull)
{
    SceneParams sp;
    sp.count = 3000;
    for (FieldKind field : {FieldKind::Ssp07, FieldKind::Zb05}) {
        const ParticleSet ps = generateScene(Scene::Drop, sp);
        Params p = Params::fromRadius(sp.radius);
        p.field = field;
        p.method = FieldMethod::GatherFull;
        const RasterizeResult full = rasterizeParticles(ps, p);
        p.method = FieldMethod::Scatter;
        const RasterizeResult scatter = rasterizeParticles(ps, p);
        EXPECT_EQ(full.stats.fieldEvaluations, scatter.stats.fieldEvaluations)
            << "same bounding volume";
        auto s = scatter.grid->getConstAccessor();
        double worst = 0;
        for (auto it = full.grid->cbeginValueOn(); it; ++it)
            worst = std::max(worst, double(std::abs(*it - s.getValue(it.getCoord()))));
        for (auto it = scatter.grid->cbeginValueOn(); it; ++it)
            worst =
                std::max(worst, double(std::abs(*it - full.grid->tree().getValue(it.getCoord()))));
        EXPECT_LE(worst, 1e-5 * sp.radius) << fieldName(field);
        expectSameZeroCrossings(*rasterizeParticles(ps, Params::fromRadius(sp.radius)).grid,
                                *scatter.grid, "scatter");
    }
}

TEST(Methods, OutputIsByteIdenticalWithOneAndTwoThreads)
{
    const ParticleSet ps = testFrame("dam_break_frame_23_24389_particles.bgeo");
    TempDir dir;
    for (int threads : {1, 2}) {
        tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        const RasterizeResult res = run(ps, FieldMethod::NarrowBand);
        io::writeLevelSet({res.grid}, dir.path(std::to_string(threads) + ".vdb"));
    }
    const std::string one = readFileBytes(dir.path("1.vdb")),
                      two = readFileBytes(dir.path("2.vdb"));
    EXPECT_GT(one.size(), 10000u);
    EXPECT_TRUE(one == two) << "the .vdb differs between 1 and 2 threads";
}

// Work and memory follow the surface: a deeper wide pool (same surface but for its side walls,
// ~4% of it at aspect 48) barely changes the band, while the volume grows with the depth.
TEST(Methods, BandFollowsTheSurfaceNotTheVolume)
{
    size_t voxels[2], volume[2];
    for (int i = 0; i < 2; ++i) {
        SceneParams sp;
        sp.count = 300000;
        sp.poolDepthScale = 1 + i;
        sp.poolAspect = 48;
        const ParticleSet ps = generateScene(Scene::Drop, sp);
        const RasterizeResult res = rasterizeParticles(ps, Params::fromRadius(sp.radius));
        voxels[i] = res.stats.activeVoxels;
        volume[i] = ps.size();
    }
    EXPECT_GT(volume[1], volume[0] * 17 / 10) << "the deeper pool holds many more particles";
    EXPECT_LT(double(voxels[1]) / double(voxels[0]), 1.05) << voxels[0] << " -> " << voxels[1];

    // One particle 1000 r away: isolated, left out, and the grid is the same.
    SceneParams sp;
    sp.count = 20000;
    ParticleSet ps = generateScene(Scene::Drop, sp);
    const RasterizeResult before = rasterizeParticles(ps, Params::fromRadius(sp.radius));
    ps.positions.push_back(Vec3f(float(1000 * sp.radius), 0.f, 0.f));
    ps.attributes.clear();
    const RasterizeResult after = rasterizeParticles(ps, Params::fromRadius(sp.radius));
    EXPECT_EQ(after.stats.activeVoxels, before.stats.activeVoxels);
    EXPECT_EQ(after.grid->tree().leafCount(), before.grid->tree().leafCount());
    EXPECT_EQ(after.isolatedParticles.back(), ps.size() - 1);
}
