// The field's arithmetic paths against independent references: the eigenvalue without
// trigonometry (FieldMath.h) against acos/cos and Jacobi rotations, the gather's sums on 4
// lanes (SSE2) and on 8 (AVX2, where the CPU has it) against the brute-force field
// (BruteForce.h), so that both paths stay tested whichever this machine takes by default, and
// the four-at-once values (FieldValueWide.h) bit for bit against fieldValue, and the 8 lanes'
// sums added at once (toFieldSumsWide) bit for bit against their grouping written out; the 8
// lanes' fused multiply-adds bit for bit against the same steps with std::fma, one lane at a
// time.
#include "field/FieldMath.h"
#include "field/FieldValue.h"
#include "field/FieldValueWide.h"
#include "field/GatherField.h"
#include "unit/field/BruteForce.h"
#include "util/Lanes.h"

#include <fluidsurf/Scenes.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <random>
#include <vector>

using namespace fluidsurf;
using namespace fluidsurf::test;

TEST(FieldMath, CosThirdOfAcosMatchesTheTrigonometricForm)
{
    double worst = 0;
    auto check = [&](double h) {
        const double err = std::abs(field::cosThirdOfAcos(h) - std::cos(std::acos(h) / 3));
        worst = std::max(worst, err);
        EXPECT_LE(err, 2e-15) << "h = " << h;
    };
    for (int i = 0; i <= 200000; ++i)
        check(-1 + 2 * i / 200000.0);
    for (int k = 1; k <= 16; ++k) // near both ends, where two roots of the cubic meet (-1)
        check(-1 + std::pow(10.0, -k)), check(1 - std::pow(10.0, -k));
    ::testing::Test::RecordProperty("worst_error", std::to_string(worst));
}

TEST(FieldMath, LargestEigenvalueMatchesJacobiRotations)
{
    auto expectMatch = [](const double a[6], const std::string& what) {
        const std::array<std::array<double, 3>, 3> m{
            {{a[0], a[1], a[2]}, {a[1], a[3], a[4]}, {a[2], a[4], a[5]}}};
        const double expected = jacobiLargestEigenvalue(m);
        double scale = 0;
        for (int k = 0; k < 6; ++k)
            scale = std::max(scale, std::abs(a[k]));
        EXPECT_NEAR(field::largestEigenvalueSym(a), expected, 1e-12 * scale) << what;
    };
    // repeated eigenvalues (the closed form's hard cases): a multiple of the identity, the
    // two largest equal (a flat surface's tangent directions), the two smallest equal
    const double identity[6] = {2, 0, 0, 2, 0, 2}, topTwo[6] = {1.5, 0, 0, 1.5, 0, 0.25},
                 bottomTwo[6] = {1.5, 0, 0, 0.25, 0, 0.25};
    expectMatch(identity, "identity");
    expectMatch(topTwo, "two largest equal");
    expectMatch(bottomTwo, "two smallest equal");
    std::mt19937_64 rng(7);
    std::uniform_real_distribution<double> u(-1, 1);
    for (int i = 0; i < 20000; ++i) {
        double a[6];
        for (double& v : a)
            v = u(rng);
        if (i % 2) // nearly repeated: a rotated diag(l, l + tiny, m)
            for (int k : {1, 2, 4})
                a[k] *= 1e-7;
        expectMatch(a, "random " + std::to_string(i));
    }
}

namespace {

/// The sums (FieldMath.h) of n particles at d from the vertex, in double, straight from their
/// definition (FieldValue.h's comment).
field::FieldSums sumsOf(const std::vector<std::array<double, 4>>& particles, double R)
{
    field::FieldSums s;
    for (const auto& p : particles) {
        const double d[3] = {p[0], p[1], p[2]};
        const double t = 1 - (d[0] * d[0] + d[1] * d[1] + d[2] * d[2]) / (R * R);
        if (t <= 0) continue;
        const double w = t * t * t;
        s.w += w, s.r += w * p[3];
        for (int a = 0; a < 3; ++a)
            s.d[a] += w * d[a], s.g[a] += t * t * d[a];
        const int pairs[6][2] = {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}};
        for (int k = 0; k < 6; ++k)
            s.m[k] += t * t * d[pairs[k][0]] * d[pairs[k][1]];
    }
    return s;
}

} // namespace

TEST(FieldMath, FourAtOnceValuesAreBitIdenticalToFieldValue)
{
    if (field::fieldLanes() != 8) GTEST_SKIP() << "this CPU has no AVX2: the path is not taken";
    const double r = 0.025, R = 4 * r;
    std::mt19937_64 rng(11);
    std::uniform_real_distribution<double> u(-1, 1);
    // neighbourhoods from empty to full: none, one particle, a line, half a ball (a surface),
    // a whole ball (inside), a thin sheet
    std::vector<field::FieldSums> sums;
    for (int trial = 0; trial < 6000; ++trial) {
        const int kind = trial % 6, count = kind == 0 ? 0 : kind == 1 ? 1 : 5 + trial % 60;
        std::vector<std::array<double, 4>> ps;
        while (int(ps.size()) < count) {
            std::array<double, 4> p{u(rng) * R, u(rng) * R, u(rng) * R, r * (1 + 0.2 * u(rng))};
            if (kind == 2) p[1] = p[2] = 0.01 * r * u(rng);
            if (kind == 3) p[2] = std::abs(p[2]) + 0.3 * r;
            if (kind == 5) p[2] = 0.05 * r * u(rng);
            ps.push_back(p);
        }
        sums.push_back(sumsOf(ps, R));
    }
    size_t compared = 0, differ = 0;
    for (const bool ssp07 : {true, false})
        for (const bool radii : {false, true}) {
            field::FieldConstants c;
            c.influenceRadius = R, c.radius = r, c.perParticleRadii = radii, c.ssp07 = ssp07;
            c.background = float(3 * r);
            // batches of 1 to 8: the tails that are padded
            for (size_t i = 0, n = 1; i < sums.size(); i += n, n = n % 8 + 1) {
                const int m = int(std::min(n, sums.size() - i));
                float wide[8];
                field::fieldValuesWide(&sums[i], m, c, wide);
                for (int k = 0; k < m; ++k, ++compared) {
                    const float one = field::fieldValue(sums[i + k], c);
                    if (std::memcmp(&one, &wide[k], sizeof one) != 0 && differ++ < 5)
                        ADD_FAILURE() << "sums " << i + k << " (ssp07 " << ssp07 << ", radii "
                                      << radii << "): " << wide[k] << " != " << one;
                }
            }
        }
    EXPECT_EQ(differ, 0u) << "of " << compared;
}

namespace {

/// Every voxel within 2 r of a particle: a band over the whole frame.
openvdb::FloatTree bandAround(const ParticleSet& ps, double voxel, double radius)
{
    openvdb::FloatTree tree(1e9f);
    const int reach = int(std::ceil(2 * radius / voxel));
    for (const Vec3f& p : ps.positions) {
        const openvdb::Coord c(int(std::floor(p.x / voxel)), int(std::floor(p.y / voxel)),
                               int(std::floor(p.z / voxel)));
        for (int x = -reach; x <= reach; ++x)
            for (int y = -reach; y <= reach; ++y)
                for (int z = -reach; z <= reach; ++z)
                    tree.setValueOn(c.offsetBy(x, y, z));
    }
    return tree;
}

void expectLanesMatchBruteForce(const ParticleSet& ps, const std::vector<float>& radii,
                                const Params& p, const std::string& what)
{
    Context ctx;
    const neighbors::CellIndex index =
        neighbors::buildCellIndex(ps.positions.data(), radii.empty() ? nullptr : radii.data(),
                                  ps.size(), p.influenceRadius, ctx);
    std::vector<std::array<double, 3>> pts;
    for (const Vec3f& v : ps.positions)
        pts.push_back({v.x, v.y, v.z});
    const std::vector<double> refRadii(radii.begin(), radii.end());
    const ReferenceParams ref{p.radius, p.influenceRadius, p.smoothingLength,          p.tLow,
                              p.tHigh,  p.background(),    p.field == FieldKind::Ssp07};
    const Level level = p.level();
    std::vector<int> lanes{4};
    if (field::fieldLanes() == 8) lanes.push_back(8);
    for (int l : lanes) {
        openvdb::FloatTree tree = bandAround(ps, p.voxelSize, p.radius);
        const size_t evaluations = field::evaluateField(tree, index, p, level, ctx, l);
        EXPECT_EQ(evaluations, tree.activeVoxelCount()) << what;
        size_t n = 0, bad = 0;
        for (auto it = tree.cbeginValueOn(); it; ++it)
            if (n++ % 7 == 0) { // a seventh of the voxels: the reference is slow
                const openvdb::Coord c = it.getCoord();
                const double expected = referencePhi(
                    pts, refRadii, {c.x() * p.voxelSize, c.y() * p.voxelSize, c.z() * p.voxelSize},
                    ref);
                if (std::abs(*it - expected) > 1e-5 * p.radius && bad++ < 5)
                    ADD_FAILURE() << what << ", " << l << " lanes: voxel " << c << " phi " << *it
                                  << " reference " << expected;
            }
        EXPECT_EQ(bad, 0u) << what << ", " << l << " lanes";
        EXPECT_GT(n, 10000u) << what;
    }
}

} // namespace

TEST(GatherField, FourAndEightLanesMatchBruteForce)
{
    SceneParams sp;
    sp.count = 2000;
    const ParticleSet ps = generateScene(Scene::Drop, sp);
    Params p = Params::fromRadius(sp.radius);
    expectLanesMatchBruteForce(ps, {}, p, "ssp07");
    std::vector<float> radii(ps.size());
    for (size_t i = 0; i < radii.size(); ++i)
        radii[i] = float(sp.radius * (0.8 + 0.4 * double(i % 11) / 10));
    expectLanesMatchBruteForce(ps, radii, p, "ssp07, per-particle radii");
    p.field = FieldKind::Zb05;
    expectLanesMatchBruteForce(ps, {}, p, "zb05");
}

// The gather reads only the particles near the box of a leaf's active voxels (GatherField.cc),
// so a voxel's value must not depend on which other voxels of its leaf are active. Each voxel
// of the drop's band leaves, evaluated with its whole leaf active, against the same voxel with
// only a few of its leaf's voxels active (corners, faces, the middle, chosen per leaf): bit for
// bit, on 4 lanes and 8, at voxel sizes that give the slab windows their shapes (a reach of 8,
// 4 and 1 slabs: voxels of r / 2, r and 4 r).
TEST(GatherField, AVoxelsValueDoesNotDependOnTheOtherActiveVoxelsOfItsLeaf)
{
    SceneParams sp;
    sp.count = 2000;
    const ParticleSet ps = generateScene(Scene::Drop, sp);
    for (double voxel : {0.5, 1.0, 4.0}) {
        Params p = Params::fromRadius(sp.radius);
        p.voxelSize = voxel * sp.radius;
        Context ctx;
        const neighbors::CellIndex index = neighbors::buildCellIndex(
            ps.positions.data(), nullptr, ps.size(), p.influenceRadius, ctx);
        std::vector<int> lanes{4};
        if (field::fieldLanes() == 8) lanes.push_back(8);
        for (int l : lanes) {
            openvdb::FloatTree whole = bandAround(ps, p.voxelSize, p.radius);
            for (auto leaf = whole.beginLeaf(); leaf; ++leaf)
                leaf->setValuesOn();
            field::evaluateField(whole, index, p, p.level(), ctx, l);
            // 1 to 4 voxels a leaf, where the field is not clamped (a clamped value would hide
            // a missing particle), spread over the leaf
            const float bound = float(0.99 * p.background());
            openvdb::FloatTree few(whole.background());
            size_t k = 0;
            for (auto leaf = whole.cbeginLeaf(); leaf; ++leaf, ++k) {
                std::vector<openvdb::Index> open;
                for (auto v = leaf->cbeginValueOn(); v; ++v)
                    if (std::abs(*v) < bound) open.push_back(v.pos());
                for (size_t m = 0; m <= k % 4 && m < open.size(); ++m)
                    few.setValueOn(leaf->offsetToGlobalCoord(open[(k + m * 97) % open.size()]));
            }
            field::evaluateField(few, index, p, p.level(), ctx, l);
            size_t compared = 0, differ = 0;
            for (auto it = few.cbeginValueOn(); it; ++it, ++compared) {
                const float alone = *it, full = whole.getValue(it.getCoord());
                if (std::memcmp(&alone, &full, sizeof alone) != 0 && differ++ < 5)
                    ADD_FAILURE() << "voxel " << voxel << " r, " << l << " lanes: " << it.getCoord()
                                  << " " << alone << " != " << full << " with its whole leaf";
            }
            EXPECT_EQ(differ, 0u) << "of " << compared;
            EXPECT_GE(compared, 10u) << voxel; // (20 at 4 r, hundreds at the others)
        }
    }
}

// The gather reads its particles four at a time with AVX2 (GatherField.cc's gatherWide, the
// floors, clamps and box test written out on lanes) or one at a time: the same particles in the
// same order, so every voxel's value must have the same bits. A drop, and a lattice whose
// coordinates are whole and half voxels (on the slabs' and the columns' edges, where a floor
// taken another way would land one lower), with and without per-particle radii, at voxels of
// r / 2, r and 4 r, every voxel of the band's leaves active and a few a leaf (other boxes).
TEST(GatherField, TheWideGatherReadsTheSameParticlesAsOneAtATime)
{
    if (util::doubleRegisterLanes() != 4) GTEST_SKIP() << "no AVX2: one way only";
    SceneParams sp;
    sp.count = 2000;
    ParticleSet drop = generateScene(Scene::Drop, sp);
    ParticleSet lattice;
    for (int i = 0; i < 14; ++i)
        for (int j = 0; j < 14; ++j)
            for (int k = 0; k < 14; ++k)
                lattice.positions.push_back(
                    Vec3f(float(i * sp.radius), float(j * sp.radius), float(k * sp.radius)));
    size_t compared = 0;
    for (const ParticleSet* ps : {&drop, &lattice})
        for (bool withRadii : {false, true})
            for (double voxel : {0.5, 1.0, 4.0}) {
                Params p = Params::fromRadius(sp.radius);
                p.voxelSize = voxel * sp.radius;
                std::vector<float> radii;
                if (withRadii)
                    for (size_t i = 0; i < ps->size(); ++i)
                        radii.push_back(float(sp.radius * (0.8 + 0.4 * double(i % 11) / 10)));
                Context ctx;
                const neighbors::CellIndex index = neighbors::buildCellIndex(
                    ps->positions.data(), withRadii ? radii.data() : nullptr, ps->size(),
                    p.influenceRadius, ctx);
                std::vector<int> lanes{4};
                if (field::fieldLanes() == 8) lanes.push_back(8);
                for (int l : lanes)
                    for (bool wholeLeaves : {true, false}) {
                        openvdb::FloatTree band = bandAround(*ps, p.voxelSize, p.radius);
                        openvdb::FloatTree tree(band.background());
                        size_t k = 0;
                        for (auto leaf = band.cbeginLeaf(); leaf; ++leaf, ++k)
                            for (auto v = leaf->cbeginValueOn(); v; ++v)
                                if (wholeLeaves || (v.pos() + k) % 61 == 0)
                                    tree.setValueOn(v.getCoord());
                        if (wholeLeaves)
                            for (auto leaf = tree.beginLeaf(); leaf; ++leaf)
                                leaf->setValuesOn();
                        openvdb::FloatTree wide = tree, narrow = tree;
                        field::detail::evaluateField(wide, index, p, p.level(), ctx, l, true);
                        field::detail::evaluateField(narrow, index, p, p.level(), ctx, l, false);
                        size_t differ = 0;
                        for (auto it = wide.cbeginValueOn(); it; ++it, ++compared) {
                            const float a = *it, b = narrow.getValue(it.getCoord());
                            if (std::memcmp(&a, &b, sizeof a) != 0 && differ++ < 5)
                                ADD_FAILURE()
                                    << (ps == &drop ? "drop" : "lattice")
                                    << (withRadii ? ", radii" : "") << ", voxel " << voxel << " r, "
                                    << l << " lanes: " << it.getCoord() << " " << a << " != " << b;
                        }
                        EXPECT_EQ(differ, 0u);
                    }
            }
    EXPECT_GT(compared, 100000u);
}

TEST(GatherField, LanesOtherThanFourOrWhatTheCpuHasAreRefused)
{
    Context ctx;
    openvdb::FloatTree tree;
    const neighbors::CellIndex index;
    const Params p = Params::fromRadius(0.025);
    for (int lanes : {0, 16, field::fieldLanes() == 8 ? 2 : 8})
        EXPECT_THROW(field::evaluateField(tree, index, p, p.level(), ctx, lanes), ValueError)
            << lanes;
}

namespace {

/// The 8-lane sums of acc, added at once (toFieldSumsWide), where the CPU has AVX2.
__attribute__((target("avx2,fma"))) field::FieldSums
wideSumsOf(const field::PartialSums<util::WideLanes>& acc)
{
    return field::toFieldSumsWide(acc);
}

} // namespace

TEST(FieldMath, EightLaneSumsAtOnceKeepTheGroupingBitForBit)
{
    if (field::fieldLanes() != 8) GTEST_SKIP() << "this CPU has no AVX2: the path is not taken";
    // lanes of mixed signs and magnitudes (1e-6 to 1e6, and zeros of either sign), where the
    // grouping of the adds decides the last bits
    std::mt19937_64 rng(5);
    std::uniform_real_distribution<double> exponent(-6, 6), sign(-1, 1);
    auto lane = [&](int i) {
        if (i % 29 == 0) return i % 2 ? -0.f : 0.f;
        return float((sign(rng) < 0 ? -1 : 1) * std::pow(10.0, exponent(rng)));
    };
    // the grouping, written out: ((v0 + v1) + (v2 + v3)) + ((v4 + v5) + (v6 + v7)) in float
    auto grouped = [](const util::WideLanes& v) {
        const float a = v[0] + v[1], b = v[2] + v[3], c = v[4] + v[5], d = v[6] + v[7];
        return double((a + b) + (c + d));
    };
    size_t compared = 0, differ = 0, orderMatters = 0;
    for (int trial = 0; trial < 20000; ++trial) {
        field::PartialSums<util::WideLanes> acc;
        util::WideLanes* all[14] = {&acc.w,  &acc.d0, &acc.d1, &acc.d2, &acc.r,  &acc.g0, &acc.g1,
                                    &acc.g2, &acc.m0, &acc.m1, &acc.m2, &acc.m3, &acc.m4, &acc.m5};
        for (int k = 0; k < 14; ++k)
            for (int l = 0; l < 8; ++l)
                (*all[k])[l] = lane(trial * 112 + k * 8 + l);
        const field::FieldSums s = wideSumsOf(acc);
        const double got[14] = {s.w,    s.d[0], s.d[1], s.d[2], s.r,    s.g[0], s.g[1],
                                s.g[2], s.m[0], s.m[1], s.m[2], s.m[3], s.m[4], s.m[5]};
        for (int k = 0; k < 14; ++k) {
            const double want = grouped(*all[k]);
            differ += std::memcmp(&got[k], &want, sizeof want) != 0;
            ++compared;
            float inOrder = 0; // the lanes added one after another: other bits, as a rule
            for (int l = 0; l < 8; ++l)
                inOrder += (*all[k])[l];
            orderMatters += double(inOrder) != want;
        }
    }
    EXPECT_EQ(differ, 0u) << "of " << compared << " sums";
    // the data can tell groupings apart: else the comparison above would prove nothing
    EXPECT_GT(orderMatters, compared / 10) << "of " << compared;
}

/// One voxel's 8-lane sums (GatherField.cc's wideSums) against its arithmetic written out in
/// scalars, lane by lane: each fused step a std::fma (rounded once, like the FMA instruction),
/// the lanes then added in laneSum's grouping. Bit for bit, for every sum, with and without
/// radii, SSP07 and ZB05: it fails if a product is rounded before its sum where the gather
/// fuses them, or fused where it does not (the values' bits are what a device must match).
TEST(FieldLanes, EightLanesFuseAsWrittenOut)
{
    if (field::fieldLanes() != 8) GTEST_SKIP() << "no AVX2 and FMA on this CPU";
    std::mt19937_64 rng(17);
    std::uniform_real_distribution<float> u(-1.1f, 1.1f), radius(0.5f, 1.5f), reach(0.8f, 1.2f);
    constexpr float kFar = 1e30f; // (the gather's padding)
    size_t compared = 0, inside = 0;
    for (int round = 0; round < 3000; ++round) {
        const uint32_t b = uint32_t(round % 5), n = 1 + uint32_t(round % 61);
        const uint32_t padded = b + (n + 7) / 8 * 8;
        std::vector<float> X(padded, kFar), Y(padded, kFar), Z(padded, kFar), R(padded, 0.f);
        for (uint32_t j = b; j < b + n; ++j)
            X[j] = u(rng), Y[j] = u(rng), Z[j] = u(rng), R[j] = radius(rng);
        const float vx = 0.2f * u(rng), vy = 0.2f * u(rng), vz = 0.2f * u(rng);
        const float span = reach(rng), invR2 = float(1.0 / (double(span) * span));
        for (const bool ssp07 : {true, false})
            for (const bool radii : {true, false}) {
                const field::FieldSums got = field::detail::wideVoxelSums(
                    X.data(), Y.data(), Z.data(), radii ? R.data() : nullptr, b, b + n, vx, vy, vz,
                    invR2, ssp07);
                float lane[14][8] = {};
                for (uint32_t j = b; j < padded; ++j) {
                    const int l = int((j - b) % 8);
                    const float ex = X[j] - vx, ey = Y[j] - vy, ez = Z[j] - vz;
                    float t = std::fma(-std::fma(ez, ez, std::fma(ex, ex, ey * ey)), invR2, 1.f);
                    t = t > 1e-6f ? t : 0.f;
                    inside += t > 0;
                    const float t2 = t * t, wt = t2 * t;
                    auto at = [&](int k) -> float& { return lane[k][l]; };
                    at(0) += wt;
                    at(1) = std::fma(wt, ex, at(1)), at(2) = std::fma(wt, ey, at(2));
                    at(3) = std::fma(wt, ez, at(3));
                    if (radii) at(4) = std::fma(wt, R[j], at(4));
                    if (ssp07) {
                        const float gx = t2 * ex, gy = t2 * ey, gz = t2 * ez;
                        at(5) += gx, at(6) += gy, at(7) += gz;
                        at(8) = std::fma(gx, ex, at(8)), at(9) = std::fma(gx, ey, at(9));
                        at(10) = std::fma(gx, ez, at(10)), at(11) = std::fma(gy, ey, at(11));
                        at(12) = std::fma(gy, ez, at(12)), at(13) = std::fma(gz, ez, at(13));
                    }
                }
                auto total = [&](int k) {
                    const float* v = lane[k];
                    return double(((v[0] + v[1]) + (v[2] + v[3])) +
                                  ((v[4] + v[5]) + (v[6] + v[7])));
                };
                const double expected[14] = {total(0),  total(1),  total(2),  total(3), total(4),
                                             total(5),  total(6),  total(7),  total(8), total(9),
                                             total(10), total(11), total(12), total(13)};
                const double actual[14] = {got.w,    got.d[0], got.d[1], got.d[2], got.r,
                                           got.g[0], got.g[1], got.g[2], got.m[0], got.m[1],
                                           got.m[2], got.m[3], got.m[4], got.m[5]};
                for (int k = 0; k < 14; ++k) {
                    ASSERT_EQ(std::memcmp(&expected[k], &actual[k], sizeof(double)), 0)
                        << "sum " << k << " (w, d, r, g, m), round " << round << ": expected "
                        << expected[k] << ", got " << actual[k];
                    ++compared;
                }
            }
    }
    EXPECT_GT(inside, size_t(20000)); // most candidates within R: the sums are not all zeros
    ::testing::Test::RecordProperty("sums_compared", std::to_string(compared));
}
