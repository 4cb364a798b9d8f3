// Particle classification against hand-countable lattices and a brute-force neighbour count.
#include "TestData.h"
#include "unit/field/BruteForce.h"

#include "classify/Classify.h"

#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Scenes.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstring>

using namespace fluidsurf;
using namespace fluidsurf::test;

namespace {
classify::Classification classifyScene(const ParticleSet& ps, const Params& p,
                                       neighbors::CellIndex& index, bool withNormals = false,
                                       int registerLanes = classify::classifyRegisterLanes())
{
    Context ctx;
    index =
        neighbors::buildCellIndex(ps.positions.data(), nullptr, ps.size(), p.smoothingLength, ctx);
    return classify::classifyParticles(index, p, ctx, classify::Outputs{true, withNormals},
                                       registerLanes);
}

/// Uniform in [-0.5, 0.5) from a 64-bit LCG (the same numbers on every platform).
double uniform(uint64_t& seed)
{
    seed = seed * 6364136223846793005ull + 1442695040888963407ull;
    return double(seed >> 11) / 9007199254740992.0 - 0.5;
}

/// Every coordinate moved by up to +-amount/2 (breaks a lattice: no pair at exactly h, where
/// float and double may round differently).
void jitter(ParticleSet& ps, uint64_t seed, double amount)
{
    for (Vec3f& v : ps.positions)
        for (int a = 0; a < 3; ++a)
            v[a] += float(uniform(seed) * amount);
}

/// A drop of `count` particles with `droplets` stray ones (Scene::Drop at the default radius,
/// sp's), every coordinate jittered by up to +-jitterRadii/2 radii (see jitter).
ParticleSet jitteredDrop(SceneParams& sp, size_t count, int droplets, uint64_t seed,
                         double jitterRadii)
{
    sp.count = count;
    sp.droplets = droplets;
    ParticleSet ps = generateScene(Scene::Drop, sp);
    jitter(ps, seed, jitterRadii * sp.radius);
    return ps;
}

/// Neighbours within h of each particle, in file order, by brute force.
std::vector<int> bruteForceCounts(const ParticleSet& ps, double h)
{
    std::vector<std::array<double, 3>> pts;
    for (const Vec3f& v : ps.positions)
        pts.push_back({v.x, v.y, v.z});
    return referenceNeighbourCounts(pts, h);
}
} // namespace

TEST(Classify, LatticeBlockOuterLayerIsSurfaceAndNothingElse)
{
    SceneParams sp;
    sp.count = 10 * 10 * 10;
    const ParticleSet ps = generateScene(Scene::Block, sp);
    const Params p = Params::fromRadius(sp.radius);
    neighbors::CellIndex index;
    const classify::Classification c = classifyScene(ps, p, index);
    size_t outer = 0;
    for (size_t i = 0; i < index.size(); ++i) {
        const Vec3f q = index.positions[i];
        bool onFace = false;
        for (int a = 0; a < 3; ++a) {
            const int cell = int(std::lround(q[a] / (2 * sp.radius)));
            onFace |= cell == 0 || cell == 9;
        }
        outer += onFace;
        EXPECT_EQ(classify::isSurface(c.classes[i]), onFace)
            << "particle at " << q.x << " " << q.y << " " << q.z << " cf " << c.colorField[i]
            << " grad " << c.colorGradient[i] << " n " << c.neighbours[i];
    }
    EXPECT_EQ(outer, 1000u - 8 * 8 * 8);
    EXPECT_EQ(c.surface + c.splash, outer);
    EXPECT_EQ(c.isolated, 0u);
}

TEST(Classify, NormalsPointOutOfTheBlockAndFollowASelection)
{
    SceneParams sp;
    sp.count = 10 * 10 * 10;
    const ParticleSet ps = generateScene(Scene::Block, sp);
    const Params p = Params::fromRadius(sp.radius);
    Context ctx;
    const neighbors::CellIndex index =
        neighbors::buildCellIndex(ps.positions.data(), nullptr, ps.size(), p.smoothingLength, ctx);
    const classify::Classification c =
        classify::classifyParticles(index, p, ctx, classify::Outputs{true, true});
    ASSERT_EQ(c.normals.size(), index.size());
    size_t faceCentres = 0;
    for (size_t i = 0; i < index.size(); ++i) {
        const Vec3f q = index.positions[i], n = c.normals[i];
        if (!classify::isSurface(c.classes[i])) {
            EXPECT_EQ(n, Vec3f(0, 0, 0)) << "interior particles have none";
            continue;
        }
        // a particle on one face, two layers away from its edges: the face's outward normal
        int cell[3], onFaces = 0, axis = 0;
        for (int a = 0; a < 3; ++a) {
            cell[a] = int(std::lround(q[a] / (2 * sp.radius)));
            if (cell[a] == 0 || cell[a] == 9) ++onFaces, axis = a;
        }
        bool central = onFaces == 1;
        for (int a = 0; a < 3; ++a)
            central &= a == axis || (cell[a] >= 2 && cell[a] <= 7);
        if (!central) continue;
        ++faceCentres;
        Vec3f out(0, 0, 0);
        out[axis] = cell[axis] == 0 ? -1.f : 1.f;
        EXPECT_GT(n.x * out.x + n.y * out.y + n.z * out.z, 0.999f)
            << q.x << " " << q.y << " " << q.z;
    }
    EXPECT_EQ(faceCentres, 6u * 6 * 6);

    // Every third particle dropped: the classes follow the particles keepParticles keeps.
    std::vector<uint8_t> keep(index.size());
    for (size_t i = 0; i < keep.size(); ++i)
        keep[i] = index.order[i] % 3 != 0;
    neighbors::CellIndex selected = index;
    neighbors::keepParticles(selected, keep);
    classify::Classification s = c;
    classify::selectClasses(s, keep);
    std::vector<size_t> at(ps.size(), SIZE_MAX); // input index -> position in index
    for (size_t i = 0; i < index.size(); ++i)
        at[index.order[i]] = i;
    ASSERT_EQ(s.classes.size(), selected.size());
    ASSERT_EQ(s.normals.size(), selected.size());
    for (size_t j = 0; j < selected.size(); ++j) {
        const size_t i = at[selected.order[j]];
        EXPECT_EQ(s.classes[j], c.classes[i]);
        EXPECT_EQ(s.neighbours[j], c.neighbours[i]);
        EXPECT_EQ(s.normals[j], c.normals[i]);
    }
}

TEST(Classify, NeighbourCountsMatchBruteForce)
{
    SceneParams sp;
    ParticleSet ps = jitteredDrop(sp, 3000, 4, 7, 0.2);
    const Params p = Params::fromRadius(sp.radius);
    neighbors::CellIndex index;
    const classify::Classification c = classifyScene(ps, p, index);
    const std::vector<int> expected = bruteForceCounts(ps, p.smoothingLength);
    for (size_t i = 0; i < index.size(); ++i)
        ASSERT_EQ(int(c.neighbours[i]), expected[index.order[i]]) << i;
    EXPECT_EQ(c.isolated, 4u) << "the drop scene's droplets";
    for (size_t i = 0; i < index.size(); ++i)
        EXPECT_EQ(c.classes[i] == classify::Isolated, expected[index.order[i]] == 0);
}

TEST(Classify, NearCoincidentPileSharesExactSums)
{
    // A pile of 2,000 particles on one spot, with float noise (as a broken simulation writes
    // them), inside a jittered drop: the pile costs one neighbourhood pass per spot, and every
    // count still matches brute force (the noise is far below the spot tolerance, h/4096).
    SceneParams sp;
    ParticleSet ps = jitteredDrop(sp, 3000, sp.droplets, 11, 0.2);
    uint64_t seed = 13;
    const uint32_t fluid = uint32_t(ps.size()), at = fluid / 2;
    const Vec3f spot = ps.positions[at];
    for (int k = 0; k < 2000; ++k)
        ps.positions.push_back(Vec3f(spot.x + float(uniform(seed) * 1e-6 * sp.radius),
                                     spot.y + float(uniform(seed) * 1e-6 * sp.radius),
                                     spot.z + float(uniform(seed) * 1e-6 * sp.radius)));
    const Params p = Params::fromRadius(sp.radius);
    neighbors::CellIndex index;
    const classify::Classification c = classifyScene(ps, p, index);
    const std::vector<int> expected = bruteForceCounts(ps, p.smoothingLength);
    size_t pile = 0;
    for (size_t i = 0; i < index.size(); ++i) {
        ASSERT_EQ(int(c.neighbours[i]), expected[index.order[i]]) << i;
        const bool inPile = index.order[i] >= fluid || index.order[i] == at;
        pile += inPile;
        if (inPile) EXPECT_GE(c.neighbours[i], 2000u);
    }
    EXPECT_EQ(pile, 2001u);
}

TEST(Classify, ColorFieldAndGradientMatchBruteForceInEitherRegisterWidth)
{
    // cf_i = poly6 sum V (h^2 - d^2)^3 and |grad cf_i| h = 6 poly6 h |sum V (h^2 - d^2)^2 d|,
    // summed here in double over every pair; the 8 float lanes must agree within float
    // rounding, and the two register widths (two SSE registers, one AVX one) bit for bit: they
    // stand for the device's sums too (cuda/src/Classify.cu runs the same lanes).
    SceneParams sp;
    ParticleSet ps = jitteredDrop(sp, 2500, 3, 5, 0.3);
    const Params p = Params::fromRadius(sp.radius);
    neighbors::CellIndex index;
    const classify::Classification four = classifyScene(ps, p, index, true, 4);
    const double h = p.smoothingLength, poly6 = 315.0 / (64.0 * M_PI * std::pow(h, 9)),
                 volume = std::pow(2 * sp.radius, 3);
    size_t checked = 0;
    for (size_t i = 0; i < index.size(); ++i) {
        double cf = 0, g[3] = {0, 0, 0};
        for (size_t j = 0; j < index.size(); ++j) {
            double d[3], d2 = 0;
            for (int a = 0; a < 3; ++a)
                d[a] = double(index.positions[j][a]) - double(index.positions[i][a]),
                d2 += d[a] * d[a];
            if (d2 >= h * h) continue;
            const double t = h * h - d2;
            cf += volume * t * t * t;
            for (int a = 0; a < 3; ++a)
                g[a] += volume * t * t * d[a];
        }
        cf *= poly6;
        const double grad = 6 * poly6 * h * std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
        ASSERT_NEAR(four.colorField[i], cf, 2e-5 * std::max(cf, 1.0)) << i;
        ASSERT_NEAR(four.colorGradient[i], grad, 2e-5) << i;
        ++checked;
    }
    EXPECT_EQ(checked, ps.size());
    Context ctx;
    if (classify::classifyRegisterLanes() != 8) {
        EXPECT_THROW(classify::classifyParticles(index, p, ctx, classify::Outputs{}, 8),
                     ValueError);
        GTEST_SKIP() << "no AVX2 here: only the SSE registers were checked";
    }
    const classify::Classification eight =
        classify::classifyParticles(index, p, ctx, classify::Outputs{true, true}, 8);
    for (size_t i = 0; i < index.size(); ++i) {
        ASSERT_EQ(four.neighbours[i], eight.neighbours[i]) << i;
        ASSERT_EQ(four.classes[i], eight.classes[i]) << i;
        ASSERT_EQ(std::memcmp(&four.colorField[i], &eight.colorField[i], sizeof(float)), 0) << i;
        ASSERT_EQ(std::memcmp(&four.colorGradient[i], &eight.colorGradient[i], sizeof(float)), 0)
            << i;
        ASSERT_EQ(std::memcmp(&four.normals[i], &eight.normals[i], sizeof(Vec3f)), 0) << i;
    }
    EXPECT_THROW(classify::classifyParticles(index, p, ctx, classify::Outputs{}, 6), ValueError);
}

namespace {
/// The lane rule of ClassRule.h written out plainly, one candidate at a time: every particle of
/// the cells its cell's box reaches (that box: the cell's particles' bounds widened by h), in
/// CellIndex::forEachCellInBox's order, candidate k on lane k % 8, coordinates relative to the
/// cell's first particle. No candidate is left out, so this is what the device sums.
/// `outOfReach` counts the groups of 8 candidates (k / 8) that have none within h.
classify::ParticleSums everyCandidate(const neighbors::CellIndex& index, size_t cell, uint32_t i,
                                      const Params& p, size_t& outOfReach)
{
    const classify::KernelConstants k = classify::kernelConstants(p);
    const uint32_t b = index.starts[cell], e = index.starts[cell + 1];
    const Vec3f o = index.positions[b];
    double lo[3] = {o.x, o.y, o.z}, hi[3] = {o.x, o.y, o.z};
    for (uint32_t j = b; j < e; ++j)
        for (int a = 0; a < 3; ++a)
            lo[a] = std::min(lo[a], double(index.positions[j][a])),
            hi[a] = std::max(hi[a], double(index.positions[j][a]));
    for (int a = 0; a < 3; ++a)
        lo[a] -= k.h, hi[a] += k.h;
    const float px = float(double(index.positions[i].x) - o.x),
                py = float(double(index.positions[i].y) - o.y),
                pz = float(double(index.positions[i].z) - o.z);
    float count[8] = {}, cf[8] = {}, gx[8] = {}, gy[8] = {}, gz[8] = {};
    size_t m = 0, inReach = 0;
    index.forEachCellInBox(lo, hi, [&](uint32_t cb, uint32_t ce) {
        for (uint32_t j = cb; j < ce; ++j, ++m) {
            const Vec3f& q = index.positions[j];
            const float dx = float(double(q.x) - o.x) - px, dy = float(double(q.y) - o.y) - py,
                        dz = float(double(q.z) - o.z) - pz;
            const double r = index.radii.empty() ? 0 : index.radii[j];
            const float v = float(index.radii.empty() ? k.uniformVolume : 8 * r * r * r);
            const float d2 = dx * dx + dy * dy + dz * dz;
            float t = k.h2 - d2;
            t = t > 0.f ? t : 0.f;
            const size_t l = m % 8;
            count[l] += d2 < k.h2 ? 1.f : 0.f;
            inReach += d2 < k.h2;
            if (l == 7) outOfReach += inReach == 0, inReach = 0; // (a last, short group aside)
            const float vt2 = v * t * t;
            cf[l] += vt2 * t;
            gx[l] += vt2 * dx, gy[l] += vt2 * dy, gz[l] += vt2 * dz;
        }
    });
    return classify::classifyLanes(count, cf, gx, gy, gz, classify::classRule(p));
}
} // namespace

TEST(Classify, GroupsOutOfReachAreSkippedWithoutChangingABit)
{
    // Classification sums only the groups of 8 candidates whose bounds come within h of the
    // particle: about half of them. The sums must still be those of every candidate, bit for
    // bit (the device sums every one), with uniform volumes and with per-particle radii.
    SceneParams sp;
    ParticleSet ps = jitteredDrop(sp, 4000, 5, 17, 0.3);
    uint64_t seed = 19;
    std::vector<float> radii(ps.size());
    for (float& r : radii)
        r = float(sp.radius * (1 + 0.4 * uniform(seed)));
    const Params p = Params::fromRadius(sp.radius);
    for (const bool withRadii : {false, true}) {
        Context ctx;
        const neighbors::CellIndex index =
            neighbors::buildCellIndex(ps.positions.data(), withRadii ? radii.data() : nullptr,
                                      ps.size(), p.smoothingLength, ctx);
        for (const int lanes : {4, classify::classifyRegisterLanes()}) {
            const classify::Classification c =
                classify::classifyParticles(index, p, ctx, classify::Outputs{true, false}, lanes);
            // the classes alone (the pipeline's call): the same classes, no sums kept
            const classify::Classification bare =
                classify::classifyParticles(index, p, ctx, classify::Outputs{}, lanes);
            ASSERT_TRUE(bare.neighbours.empty() && bare.colorField.empty() &&
                        bare.colorGradient.empty() && bare.normals.empty());
            ASSERT_TRUE(std::equal(c.classes.begin(), c.classes.end(), bare.classes.begin(),
                                   bare.classes.end()));
            EXPECT_EQ(bare.interior, c.interior);
            EXPECT_EQ(bare.surface, c.surface);
            size_t checked = 0, interior = 0, outOfReach = 0;
            for (size_t cell = 0; cell < index.cellCount(); ++cell)
                for (uint32_t i = index.starts[cell]; i < index.starts[cell + 1]; ++i) {
                    const classify::ParticleSums s = everyCandidate(index, cell, i, p, outOfReach);
                    ASSERT_EQ(c.neighbours[i], s.neighbours) << i;
                    ASSERT_EQ(std::memcmp(&c.colorField[i], &s.colorField, sizeof(float)), 0)
                        << i << ": " << c.colorField[i] << " against " << s.colorField;
                    ASSERT_EQ(std::memcmp(&c.colorGradient[i], &s.gradient, sizeof(float)), 0)
                        << i << ": " << c.colorGradient[i] << " against " << s.gradient;
                    ASSERT_EQ(c.classes[i], s.cls) << i;
                    ++checked, interior += s.cls == classify::Interior;
                }
            EXPECT_EQ(checked, ps.size());
            EXPECT_GT(interior, ps.size() / 10);
            EXPECT_GT(outOfReach, 2 * checked) << "groups to skip: more than two a particle";
        }
    }
}

TEST(Classify, CountsAndIsolatedListTallyTheClassesOverManyChunks)
{
    // more particles than one chunk of the counts' parallel reduce (65,536), with stray ones
    SceneParams sp;
    const ParticleSet ps = jitteredDrop(sp, 300000, 40, 7, 0.2);
    const Params p = Params::fromRadius(sp.radius);
    neighbors::CellIndex index;
    const classify::Classification c = classifyScene(ps, p, index);
    size_t tally[4] = {0, 0, 0, 0};
    std::vector<uint32_t> isolated; // input indices, by a loop of its own
    for (size_t i = 0; i < c.classes.size(); ++i) {
        ASSERT_LT(c.classes[i], 4);
        ++tally[c.classes[i]];
        if (c.classes[i] == classify::Isolated) isolated.push_back(index.order[i]);
    }
    EXPECT_EQ(c.interior, tally[classify::Interior]);
    EXPECT_EQ(c.surface, tally[classify::Surface]);
    EXPECT_EQ(c.splash, tally[classify::Splash]);
    EXPECT_EQ(c.isolated, tally[classify::Isolated]);
    EXPECT_GT(c.interior, ps.size() / 2);
    EXPECT_GE(c.isolated, 20u) << "the stray particles";

    // the pipeline's list of the particles it leaves out: the same ones, ascending
    std::sort(isolated.begin(), isolated.end());
    const RasterizeResult res = rasterizeParticles(ps, p);
    EXPECT_EQ(res.isolatedParticles, isolated);
    EXPECT_EQ(res.stats.isolated, c.isolated);
}
