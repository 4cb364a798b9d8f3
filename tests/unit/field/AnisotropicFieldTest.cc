// The ssp07-aniso field (issue 64): phi at the band's voxels against a brute force over all
// particles whose J comes from central differences of x-bar (not the gather's analytic sums);
// spheres give SSP07's field; a jittered slab's top comes out flatter than SSP07's; the same
// bytes on one thread; parameters checked.
#include "field/AnisotropicField.h"
#include "anisotropy/KernelShapes.h"
#include "classify/Classify.h"
#include "field/FieldMath.h"
#include "field/GatherField.h"
#include "unit/field/PipelineKernels.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/MeshLevelSet.h>
#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Scenes.h>

#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <algorithm>
#include <array>
#include <cmath>

using namespace fluidsurf;

namespace {

Params anisoParams(double r)
{
    Params p = Params::fromRadius(r);
    p.field = FieldKind::Ssp07Aniso;
    return p;
}

/// The kernels as the pipeline makes them (KernelShapes is tested against its own brute force),
/// in input order.
struct Kernels
{
    std::vector<Vec3f> centres;
    std::vector<std::array<double, 6>> g;
    std::vector<bool> isolated;
};

Kernels kernelsOf(const ParticleSet& ps, const Params& p)
{
    Context ctx;
    const double cellSize = std::min(p.influenceRadius, p.smoothingLength);
    const neighbors::CellIndex index =
        neighbors::buildCellIndex(ps.positions.data(), nullptr, ps.size(), cellSize, ctx);
    const classify::Classification classes = classify::classifyParticles(index, p, ctx);
    const anisotropy::KernelShapes shapes =
        anisotropy::kernelShapes(index, classes, anisotropy::shapeParams(p), ctx);
    Kernels k;
    k.centres.resize(ps.size()), k.g.resize(ps.size()), k.isolated.resize(ps.size());
    for (size_t i = 0; i < ps.size(); ++i) {
        const uint32_t input = index.order[i];
        k.centres[input] = shapes.centres[i];
        for (int q = 0; q < 6; ++q)
            k.g[input][q] = shapes.shapes[6 * i + q];
        k.isolated[input] = classes.classes[i] == classify::Isolated;
    }
    return k;
}

/// x-bar at x and the weight sum, over all kernels, in double.
double xbar(const Kernels& k, const double x[3], double out[3])
{
    double w = 0;
    out[0] = out[1] = out[2] = 0;
    for (size_t j = 0; j < k.centres.size(); ++j) {
        if (k.isolated[j]) continue;
        const auto& g = k.g[j];
        const double d[3] = {k.centres[j].x - x[0], k.centres[j].y - x[1], k.centres[j].z - x[2]};
        const double u[3] = {g[0] * d[0] + g[1] * d[1] + g[2] * d[2],
                             g[1] * d[0] + g[3] * d[1] + g[4] * d[2],
                             g[2] * d[0] + g[4] * d[1] + g[5] * d[2]};
        const double t = 1 - (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        if (!(t > 1e-6)) continue;
        const double wj = t * t * t;
        w += wj;
        for (int a = 0; a < 3; ++a)
            out[a] += wj * k.centres[j][a];
    }
    for (int a = 0; a < 3; ++a)
        out[a] /= w;
    return w;
}

/// phi at x: |x - x-bar| - r f(EV_max of the symmetric part of grad x-bar), the gradient by
/// central differences (step 1e-6 R).
double bruteForcePhi(const Kernels& k, const Params& p, const double x[3])
{
    double xb[3];
    if (!(xbar(k, x, xb) > 0)) return p.background();
    double J[3][3];
    const double step = 1e-6 * p.influenceRadius;
    for (int b = 0; b < 3; ++b) {
        double xp[3] = {x[0], x[1], x[2]}, xm[3] = {x[0], x[1], x[2]}, bp[3], bm[3];
        xp[b] += step, xm[b] -= step;
        xbar(k, xp, bp), xbar(k, xm, bm);
        for (int a = 0; a < 3; ++a)
            J[a][b] = (bp[a] - bm[a]) / (2 * step);
    }
    const double sym[6] = {J[0][0], 0.5 * (J[0][1] + J[1][0]), 0.5 * (J[0][2] + J[2][0]),
                           J[1][1], 0.5 * (J[1][2] + J[2][1]), J[2][2]};
    const double ev = field::largestEigenvalueSym(sym);
    double f = 1;
    if (ev >= p.tLow) {
        const double gamma = std::clamp((p.tHigh - ev) / (p.tHigh - p.tLow), 0.0, 1.0);
        f = gamma * gamma * gamma - 3 * gamma * gamma + 3 * gamma;
    }
    const double dist = std::hypot(x[0] - xb[0], x[1] - xb[1], x[2] - xb[2]);
    return std::clamp(dist - p.radius * f, -p.background(), p.background());
}

} // namespace

TEST(AnisotropicField, MatchesABruteForceWithNumericalGradients)
{
    for (Scene scene : {Scene::Sheet, Scene::Drop}) {
        SceneParams sp;
        sp.radius = 0.025, sp.count = 1500, sp.layers = 2, sp.jitter = 0.3, sp.seed = 7;
        const ParticleSet ps = generateScene(scene, sp);
        Params p = anisoParams(sp.radius);
        p.anisotropyRatio = 2.5, p.centreSmoothing = 0.3; // stretched and moved, beyond defaults
        const Kernels kernels = kernelsOf(ps, p);
        Context ctx;
        const RasterizeResult res = rasterizeParticles(ps, p, ctx);
        size_t checked = 0, bad = 0;
        double worst = 0;
        size_t n = 0;
        for (auto v = res.grid->tree().cbeginValueOn(); v; ++v, ++n) {
            if (n % 17) continue; // a sample: the brute force costs 7 passes over all particles
            const openvdb::Coord c = v.getCoord();
            const double x[3] = {c.x() * p.voxelSize, c.y() * p.voxelSize, c.z() * p.voxelSize};
            const double want = bruteForcePhi(kernels, p, x), err = std::fabs(*v - want);
            worst = std::max(worst, err);
            bad += err > 1e-4 * sp.radius;
            ++checked;
        }
        EXPECT_GT(checked, 500u) << sceneName(scene);
        EXPECT_EQ(bad, 0u) << sceneName(scene) << ": worst " << worst / sp.radius << " r";
    }
}

TEST(AnisotropicField, SpheresGiveSsp07sField)
{
    SceneParams sp;
    sp.radius = 0.025, sp.count = 8000, sp.jitter = 0.3;
    const ParticleSet ps = generateScene(Scene::Drop, sp);
    Params aniso = anisoParams(sp.radius);
    aniso.anisotropyRatio = 1; // every kernel the sphere of radius R
    const Params ssp07 = Params::fromRadius(sp.radius);
    Context ctx;
    const RasterizeResult a = rasterizeParticles(ps, aniso, ctx),
                          b = rasterizeParticles(ps, ssp07, ctx);
    EXPECT_EQ(a.grid->activeVoxelCount(), b.grid->activeVoxelCount());
    const auto acc = b.grid->getConstAccessor();
    double worst = 0;
    for (auto v = a.grid->tree().cbeginValueOn(); v; ++v)
        worst = std::max(worst, double(std::fabs(*v - acc.getValue(v.getCoord()))));
    EXPECT_LT(worst, 1e-5 * sp.radius) << "the gather's float lanes against double";
}

TEST(AnisotropicField, AJitteredSlabsTopIsFlatterThanSsp07s)
{
    SceneParams sp;
    sp.radius = 0.025, sp.count = 12000, sp.layers = 5, sp.jitter = 0.3, sp.seed = 11;
    const ParticleSet slab = generateScene(Scene::Slab, sp);
    double top = -1e300, lo = 1e300, hi = -1e300;
    for (const Vec3f& q : slab.positions)
        top = std::max(top, double(q.z)), lo = std::min(lo, double(q.x)),
        hi = std::max(hi, double(q.x));
    auto rms = [&](const TriangleMesh& m) { // heights over the middle 60% of the top face
        double sum = 0, sum2 = 0;
        size_t n = 0;
        for (const Vec3f& q : m.points) {
            const double a = lo + 0.2 * (hi - lo), b = hi - 0.2 * (hi - lo);
            if (q.x > a && q.x < b && q.y > a && q.y < b && q.z > top)
                sum += q.z, sum2 += double(q.z) * q.z, ++n;
        }
        EXPECT_GT(n, 1000u);
        return std::sqrt(sum2 / n - (sum / n) * (sum / n));
    };
    Context ctx;
    const TriangleMesh ssp07 =
        meshLevelSet(*rasterizeParticles(slab, Params::fromRadius(sp.radius), ctx).grid,
                     Mesher::MarchingCubes, ctx);
    const TriangleMesh aniso = meshLevelSet(
        *rasterizeParticles(slab, anisoParams(sp.radius), ctx).grid, Mesher::MarchingCubes, ctx);
    const MeshReport report = checkMesh(aniso);
    EXPECT_TRUE(report.watertight()) << describe(report);
    EXPECT_EQ(report.components, 1u);
    // measured 0.33x at J = 0.2 and 0.42x at J = 0.4 (20,000 particles, 6 layers)
    EXPECT_LT(rms(aniso), 0.6 * rms(ssp07));
}

TEST(AnisotropicField, SameBytesOnOneThreadAndParametersChecked)
{
    SceneParams sp;
    sp.radius = 0.025, sp.count = 6000, sp.jitter = 0.3;
    const ParticleSet ps = generateScene(Scene::Drop, sp);
    const Params p = anisoParams(sp.radius);
    Context ctx;
    const RasterizeResult all = rasterizeParticles(ps, p, ctx);
    {
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        const RasterizeResult single = rasterizeParticles(ps, p, ctx);
        ASSERT_EQ(all.grid->activeVoxelCount(), single.grid->activeVoxelCount());
        const auto acc = single.grid->getConstAccessor();
        size_t differ = 0;
        for (auto v = all.grid->tree().cbeginValueOn(); v; ++v)
            differ += *v != acc.getValue(v.getCoord());
        EXPECT_EQ(differ, 0u);
    }
    Params bad = p;
    bad.method = FieldMethod::GatherFull;
    EXPECT_THROW(bad.validate(), ValueError);
    bad = p, bad.adaptive = true;
    EXPECT_THROW(bad.validate(), ValueError);
    bad = p, bad.anisotropyRatio = 9;
    EXPECT_THROW(bad.validate(), ValueError);
    bad = p, bad.centreSmoothing = -0.1;
    EXPECT_THROW(bad.validate(), ValueError);
    bad = p, bad.anisotropyRadius = 0;
    EXPECT_THROW(bad.validate(), ValueError);
    EXPECT_EQ(fieldFromName("ssp07-aniso"), FieldKind::Ssp07Aniso);
    EXPECT_STREQ(fieldName(FieldKind::Ssp07Aniso), "ssp07-aniso");
}

namespace {
void expectTheSameBitsEverywhere(FieldKind kind)
{
    // The device tests kernels voxel by voxel, the host per block of a leaf's active box: the
    // bits must not depend on which kernels a test lets through (AnisotropicSums.h). Here the
    // eight-lane sums against one voxel at a time, and a checkerboard of the band's voxels (other
    // boxes, other lists) against the whole band.
    SceneParams sp;
    sp.radius = 0.025, sp.count = 4000, sp.layers = 2, sp.jitter = 0.3, sp.seed = 5;
    const ParticleSet ps = generateScene(Scene::Sheet, sp);
    Params p = anisoParams(sp.radius);
    p.field = kind, p.anisotropyRatio = 2.5, p.centreSmoothing = 0.3;
    SCOPED_TRACE(fieldName(kind));
    Context ctx;
    const RasterizeResult band = rasterizeParticles(ps, p, ctx); // the pipeline's own values
    const auto made = testing_support::pipelineKernels(ps, p, ctx);
    const field::AnisotropicKernels& kernels = made->table;
    const Level level = p.level();
    auto evaluate = [&](bool wide, bool checkerboard) {
        auto tree =
            std::make_shared<openvdb::FloatTree>(band.grid->tree(), 0.f, openvdb::TopologyCopy());
        if (checkerboard)
            for (auto v = tree->beginValueOn(); v; ++v) {
                const openvdb::Coord c = v.getCoord();
                if ((c.x() + c.y() + c.z()) & 1) v.setValueOff();
            }
        field::detail::evaluateAnisotropicField(*tree, kernels, p, level, ctx, wide);
        return tree;
    };
    const auto scalar = evaluate(false, false), half = evaluate(false, true);
    std::vector<std::shared_ptr<openvdb::FloatTree>> others{half};
    if (field::fieldLanes() == 8) others.push_back(evaluate(true, true));
    const auto reference = band.grid->getConstAccessor();
    size_t differ = 0, checked = 0;
    for (auto v = scalar->cbeginValueOn(); v; ++v, ++checked)
        differ += *v != reference.getValue(v.getCoord());
    EXPECT_GT(checked, 10000u);
    EXPECT_EQ(differ, 0u) << "one voxel at a time against the pipeline's (eight a register where "
                             "the CPU has AVX2)";
    for (const auto& tree : others) {
        size_t mismatched = 0, n = 0;
        for (auto v = tree->cbeginValueOn(); v; ++v, ++n)
            mismatched += *v != reference.getValue(v.getCoord());
        EXPECT_GT(n, checked / 3);
        EXPECT_EQ(mismatched, 0u) << "a checkerboard of the band";
    }
}
} // namespace

TEST(AnisotropicField, WideAndScalarSumsAndAnySubsetOfVoxelsGiveTheSameBits)
{
    expectTheSameBitsEverywhere(FieldKind::Ssp07Aniso);
    expectTheSameBitsEverywhere(FieldKind::Yt10);
}

namespace {

/// [YT10]'s density at x over all kernels, in double: sum_j (2r)^3 315 / (64 pi) det(G_j)
/// (1 - |G_j (c_j - x)|^2)^3.
double bruteForceDensity(const Kernels& k, double r, const double x[3])
{
    double sum = 0;
    for (size_t j = 0; j < k.centres.size(); ++j) {
        if (k.isolated[j]) continue;
        const auto& g = k.g[j];
        const double d[3] = {k.centres[j].x - x[0], k.centres[j].y - x[1], k.centres[j].z - x[2]};
        const double u[3] = {g[0] * d[0] + g[1] * d[1] + g[2] * d[2],
                             g[1] * d[0] + g[3] * d[1] + g[4] * d[2],
                             g[2] * d[0] + g[4] * d[1] + g[5] * d[2]};
        const double t = 1 - (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
        if (!(t > 1e-6)) continue;
        const double det = g[0] * (g[3] * g[5] - g[4] * g[4]) - g[1] * (g[1] * g[5] - g[4] * g[2]) +
                           g[2] * (g[1] * g[4] - g[3] * g[2]);
        sum += 8 * r * r * r * 315 / (64 * M_PI) * det * t * t * t;
    }
    return sum;
}

} // namespace

TEST(AnisotropicField, Yt10MatchesABruteForceDensity)
{
    for (Scene scene : {Scene::Sheet, Scene::Drop}) {
        SceneParams sp;
        sp.radius = 0.025, sp.count = 1500, sp.layers = 2, sp.jitter = 0.3, sp.seed = 7;
        const ParticleSet ps = generateScene(scene, sp);
        Params p = anisoParams(sp.radius);
        p.field = FieldKind::Yt10, p.anisotropyRatio = 2.5, p.centreSmoothing = 0.3;
        const Kernels kernels = kernelsOf(ps, p);
        Context ctx;
        const RasterizeResult res = rasterizeParticles(ps, p, ctx);
        size_t checked = 0, bad = 0, crossings = 0;
        double worst = 0;
        size_t n = 0;
        for (auto v = res.grid->tree().cbeginValueOn(); v; ++v, ++n) {
            if (n % 5) continue;
            const openvdb::Coord c = v.getCoord();
            const double x[3] = {c.x() * p.voxelSize, c.y() * p.voxelSize, c.z() * p.voxelSize};
            const double want = std::clamp((p.isoLevel - bruteForceDensity(kernels, sp.radius, x)) *
                                               p.influenceRadius,
                                           -p.background(), p.background());
            const double err = std::fabs(*v - want);
            worst = std::max(worst, err);
            bad += err > 1e-4 * sp.radius;
            crossings += std::fabs(want) < p.voxelSize;
            ++checked;
        }
        EXPECT_GT(checked, 1000u) << sceneName(scene);
        EXPECT_GT(crossings, 100u) << sceneName(scene) << ": the band holds the surface";
        EXPECT_EQ(bad, 0u) << sceneName(scene) << ": worst " << worst / sp.radius << " r";
    }
}

TEST(AnisotropicField, Yt10PutsALatticeFaceWhereItsParticlesVolumesEnd)
{
    // A normalised kernel smooths the particles' volumes, (2r)^3 each, into a density that a
    // half-space of fluid takes to 1/2 at its boundary (the kernel is symmetric): on a lattice,
    // r above the top layer's centres, so a block of N particles encloses about N (2r)^3. With
    // anisotropy ratio 1 every kernel is the sphere of R.
    SceneParams sp;
    sp.radius = 0.025, sp.count = 20000, sp.jitter = 0;
    const ParticleSet block = generateScene(Scene::Block, sp);
    Params p = anisoParams(sp.radius);
    p.field = FieldKind::Yt10, p.anisotropyRatio = 1;
    Context ctx;
    const TriangleMesh mesh =
        meshLevelSet(*rasterizeParticles(block, p, ctx).grid, Mesher::MarchingCubes, ctx);
    const MeshReport report = checkMesh(mesh);
    EXPECT_TRUE(report.watertight()) << describe(report);
    EXPECT_EQ(report.components, 1u);
    const double ratio = report.volume / (double(block.size()) * std::pow(2 * sp.radius, 3));
    EXPECT_NEAR(ratio, 1.0, 0.02);
    double top = -1e300, lo = 1e300, hi = -1e300;
    for (const Vec3f& q : block.positions)
        top = std::max(top, double(q.z)), lo = std::min(lo, double(q.x)),
        hi = std::max(hi, double(q.x));
    double sum = 0;
    size_t n = 0;
    for (const Vec3f& q : mesh.points) { // the top face away from its edges
        const double a = lo + 0.3 * (hi - lo), b = hi - 0.3 * (hi - lo);
        if (q.x > a && q.x < b && q.y > a && q.y < b && q.z > top) sum += q.z, ++n;
    }
    ASSERT_GT(n, 50u);
    EXPECT_NEAR(sum / double(n) - top, sp.radius, 0.05 * sp.radius);
    ::testing::Test::RecordProperty("block_volume_ratio", std::to_string(ratio));
}
