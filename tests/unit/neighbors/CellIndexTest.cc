// The Z-order cell index: keys, ranges and lookups against direct computation.
#include "neighbors/CellIndex.h"

#include <fluidsurf/Error.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <set>
#include <utility>
#include <vector>

using namespace fluidsurf;
using namespace fluidsurf::neighbors;

TEST(CellIndex, MortonKeyInterleavesBits)
{
    for (uint32_t x : {0u, 1u, 5u, 1234567u, (1u << 21) - 1})
        for (uint32_t y : {0u, 3u, 777777u})
            for (uint32_t z : {0u, 2u, 2097151u}) {
                uint64_t expected = 0;
                for (int b = 0; b < 21; ++b)
                    expected |= uint64_t((x >> b) & 1) << (3 * b) |
                                uint64_t((y >> b) & 1) << (3 * b + 1) |
                                uint64_t((z >> b) & 1) << (3 * b + 2);
                ASSERT_EQ(mortonKey(x, y, z), expected);
            }
}

TEST(CellIndex, EveryParticleIsInItsCellAndFound)
{
    std::vector<Vec3f> pts;
    uint64_t s = 42;
    for (int i = 0; i < 5000; ++i) {
        auto u = [&] {
            s = s * 6364136223846793005ull + 1442695040888963407ull;
            return float(s >> 40) / float(1 << 24);
        };
        pts.emplace_back(u() * 3 - 1, u() * 2, u() * 0.5f - 7);
    }
    // far away: sparse, not a dense box, and 10,000 cells along x, past the 1,024 that 32-bit
    // keys hold (ManyCellsAcrossChunksAreAllFoundAndNoOthers has 80: the 32-bit keys)
    pts.emplace_back(1000.f, 0.f, -7.f);
    const double cell = 0.1;
    Context ctx;
    const CellIndex index = buildCellIndex(pts.data(), nullptr, pts.size(), cell, ctx);
    ASSERT_EQ(index.size(), pts.size());
    EXPECT_LT(index.cellCount(), pts.size() + 1);
    std::set<uint32_t> seen(index.order.begin(), index.order.end());
    EXPECT_EQ(seen.size(), pts.size());
    for (size_t c = 0; c + 1 < index.keys.size(); ++c)
        ASSERT_LT(index.keys[c], index.keys[c + 1]);
    for (size_t i = 0; i < index.size(); ++i) {
        const Vec3f& p = pts[index.order[i]];
        ASSERT_EQ(index.positions[i], p);
        int64_t cc[3];
        for (int a = 0; a < 3; ++a)
            cc[a] = int64_t(std::floor((p[a] - index.origin[a]) / cell));
        const CellRange r = index.find(cc[0], cc[1], cc[2]);
        ASSERT_TRUE(i >= r.begin && i < r.end) << i;
    }
    EXPECT_TRUE(index.find(-1, 0, 0).empty());
    // keepParticles keeps order and ranges
    std::vector<uint8_t> keep(index.size());
    for (size_t i = 0; i < keep.size(); ++i)
        keep[i] = i % 3 != 0;
    CellIndex sub = index;
    keepParticles(sub, keep);
    size_t kept = 0;
    for (uint8_t k : keep)
        kept += k;
    ASSERT_EQ(sub.size(), kept);
    for (size_t c = 0; c < sub.keys.size(); ++c)
        for (uint32_t i = sub.starts[c]; i < sub.starts[c + 1]; ++i) {
            const CellRange r = index.find(index.cellCoord(sub.positions[i].x, 0),
                                           index.cellCoord(sub.positions[i].y, 1),
                                           index.cellCoord(sub.positions[i].z, 2));
            ASSERT_FALSE(r.empty());
        }
}

TEST(CellIndex, SortsByCellThenInputOrderAsDirectComputation)
{
    // Particles on cell borders (multiples of half a cell, exact in float and double), on the
    // grid's far side, in random order, a count that is not a multiple of four (the keys are
    // found four at a time where the CPU has AVX2); with 32-bit keys and, with one particle
    // 5,000 cells away, 64-bit ones. The order must be the stable sort by each particle's
    // cell, found here with std::floor.
    uint64_t s = 99;
    auto u = [&] {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        return uint32_t(s >> 33);
    };
    for (const bool far : {false, true}) {
        std::vector<Vec3f> pts;
        for (int i = 0; i < 4003; ++i) {
            Vec3f p(float(u() % 64) * 0.125f, float(u() % 16) * 0.125f - 3,
                    float(u() % 40) * 0.125f);
            if (i % 3 == 0) p.x += float(u() % 1000) * 1e-4f; // between the borders too
            pts.push_back(p);
        }
        if (far) pts[1234] = Vec3f(1250.f, -3.f, 0.f);
        const double cell = 0.25;
        Context ctx;
        const CellIndex index = buildCellIndex(pts.data(), nullptr, pts.size(), cell, ctx);
        std::vector<std::pair<uint64_t, uint32_t>> expected;
        for (uint32_t i = 0; i < pts.size(); ++i) {
            int64_t c[3];
            for (int a = 0; a < 3; ++a) {
                c[a] = int64_t(std::floor((double(pts[i][a]) - index.origin[a]) / cell));
                ASSERT_GE(c[a], 0);
                ASSERT_LT(c[a], int64_t(index.dims[a]));
            }
            expected.push_back({mortonKey(uint32_t(c[0]), uint32_t(c[1]), uint32_t(c[2])), i});
        }
        EXPECT_EQ(index.dims[0] > 1024, far);
        std::sort(expected.begin(), expected.end()); // by key, then by input order
        ASSERT_EQ(index.order.size(), pts.size());
        size_t cells = 0;
        for (size_t k = 0; k < expected.size(); ++k) {
            ASSERT_EQ(index.order[k], expected[k].second) << k;
            ASSERT_EQ(index.positions[k], pts[expected[k].second]) << k;
            if (k == 0 || expected[k].first != expected[k - 1].first) {
                ASSERT_LT(cells, index.keys.size());
                EXPECT_EQ(index.keys[cells], expected[k].first);
                EXPECT_EQ(index.starts[cells], k);
                ++cells;
            }
        }
        EXPECT_EQ(cells, index.cellCount());
    }
}

TEST(CellIndex, RejectsSpansBeyondTheKey)
{
    std::vector<Vec3f> pts{{0, 0, 0}, {0, 3e6f, 0}};
    Context ctx;
    EXPECT_THROW(buildCellIndex(pts.data(), nullptr, pts.size(), 1.0, ctx), ValueError);
}

TEST(CellIndex, ManyCellsAcrossChunksAreAllFoundAndNoOthers)
{
    // 300,000 particles over ~150,000 cells: the cells are found in chunks of 65,536 particles
    // and the hash table is filled by many tasks at once. Every particle's cell range must hold
    // it and only particles of that cell, and a cell without particles must not be found.
    std::vector<Vec3f> pts;
    uint64_t s = 7;
    auto u = [&] {
        s = s * 6364136223846793005ull + 1442695040888963407ull;
        return float(s >> 40) / float(1 << 24);
    };
    for (int i = 0; i < 300000; ++i)
        pts.emplace_back(u() * 8, u() * 8, u() * 4);
    const double cell = 0.1; // 80 x 80 x 40 = 256,000 cells, most of them occupied
    Context ctx;
    const CellIndex index = buildCellIndex(pts.data(), nullptr, pts.size(), cell, ctx);
    std::set<std::array<int64_t, 3>> occupied;
    auto cellOf = [&](const Vec3f& p) {
        std::array<int64_t, 3> cc;
        for (int a = 0; a < 3; ++a)
            cc[a] = index.cellCoord(p[a], a);
        return cc;
    };
    for (const Vec3f& p : pts)
        occupied.insert(cellOf(p));
    ASSERT_EQ(index.cellCount(), occupied.size());
    ASSERT_EQ(index.starts.size(), index.cellCount() + 1);
    ASSERT_EQ(index.starts.back(), pts.size());
    for (size_t c = 0; c < index.cellCount(); ++c)
        ASSERT_LT(index.starts[c], index.starts[c + 1]) << c;
    for (size_t i = 0; i < index.size(); ++i) {
        const std::array<int64_t, 3> cc = cellOf(index.positions[i]);
        const CellRange r = index.find(cc[0], cc[1], cc[2]);
        ASSERT_TRUE(i >= r.begin && i < r.end) << i;
        for (uint32_t j = r.begin; j < r.end; ++j)
            ASSERT_EQ(cellOf(index.positions[j]), cc) << i << " " << j;
    }
    size_t empty = 0;
    for (int64_t z = 0; z < index.dims[2]; ++z)
        for (int64_t y = 0; y < index.dims[1]; ++y)
            for (int64_t x = 0; x < index.dims[0]; ++x)
                if (!occupied.count({x, y, z})) {
                    ASSERT_TRUE(index.find(x, y, z).empty()) << x << " " << y << " " << z;
                    ++empty;
                }
    EXPECT_GT(empty, 10000u); // the lookup was asked about cells it must not find
}

TEST(CellIndex, BrickKeysStartInOneRunOfSlots)
{
    // The 64 keys of a 4x4x4 brick (Morton keys equal but for their lowest 6 bits) start in one
    // run of 64 slots, each at its place in the brick: a neighbourhood's look-ups share cache
    // lines. Any table size (down to the smallest, 16 slots) keeps each slot in the table.
    for (uint64_t mask : {uint64_t(15), uint64_t(63), uint64_t(1023), (uint64_t(1) << 26) - 1})
        for (uint32_t bx : {0u, 1u, 77u, 4000u})
            for (uint32_t by : {0u, 5u, 131071u})
                for (uint32_t bz : {0u, 3u}) {
                    const uint64_t first = cellSlot(mortonKey(4 * bx, 4 * by, 4 * bz), mask);
                    for (uint32_t i = 0; i < 64; ++i) {
                        const uint64_t key =
                            mortonKey(4 * bx + (i & 3), 4 * by + (i >> 2 & 3), 4 * bz + (i >> 4));
                        const uint64_t slot = cellSlot(key, mask);
                        ASSERT_LE(slot, mask);
                        ASSERT_EQ(slot & ~uint64_t(63) & mask, first & ~uint64_t(63) & mask);
                        ASSERT_EQ(slot & 63 & mask, key & 63 & mask);
                    }
                }
}

TEST(CellIndex, CrowdedSlotsAreAllFoundAndNoOthers)
{
    // Layouts that crowd the table's runs of slots: full bricks side by side (their runs collide
    // whole), every occupied cell at the same place in its brick (a lattice of stride 4 cells),
    // and a row of cells 64 apart. Every occupied cell must be found with its own particles,
    // and every empty cell in the grid must not be.
    const double cell = 1.0;
    std::vector<std::vector<std::array<int, 3>>> layouts(3);
    for (int z = 0; z < 24; ++z)
        for (int y = 0; y < 24; ++y)
            for (int x = 0; x < 40; ++x)
                layouts[0].push_back({x, y, z});
    for (int z = 0; z < 64; z += 4)
        for (int y = 0; y < 64; y += 4)
            for (int x = 0; x < 128; x += 4)
                layouts[1].push_back({x, y, z});
    for (int x = 0; x < 64 * 300; x += 64)
        layouts[2].push_back({x, 5, 9});
    for (const auto& cells : layouts) {
        std::vector<Vec3f> pts;
        for (const auto& c : cells)
            pts.emplace_back(float(c[0] + 0.5), float(c[1] + 0.5), float(c[2] + 0.5));
        Context ctx;
        const CellIndex index = buildCellIndex(pts.data(), nullptr, pts.size(), cell, ctx);
        ASSERT_EQ(index.cellCount(), cells.size());
        std::set<std::array<int64_t, 3>> occupied;
        for (size_t i = 0; i < index.size(); ++i) {
            std::array<int64_t, 3> cc;
            for (int a = 0; a < 3; ++a)
                cc[a] = index.cellCoord(index.positions[i][a], a);
            occupied.insert(cc);
            const CellRange r = index.find(cc[0], cc[1], cc[2]);
            ASSERT_EQ(r.end - r.begin, 1u) << i;
            ASSERT_EQ(r.begin, i);
        }
        ASSERT_EQ(occupied.size(), cells.size());
        for (int64_t z = 0; z < index.dims[2]; ++z)
            for (int64_t y = 0; y < index.dims[1]; ++y)
                for (int64_t x = 0; x<index.dims[0]; x += index.dims[0]> 1000 ? 7 : 1)
                    if (!occupied.count({x, y, z}))
                        ASSERT_TRUE(index.find(x, y, z).empty()) << x << " " << y << " " << z;
    }
}

TEST(CellIndex, KeepParticlesGivesWhatOneThreadMovingThemDownGives)
{
    // reference: the kept particles copied out in order, the cells with any kept particle, each
    // starting at the count kept before it; several chunks of particles (65,536 a chunk), few
    // dropped (the parallel moves with their waiting ones) and many (one thread)
    std::vector<Vec3f> points(300000);
    std::vector<float> radii(points.size());
    uint64_t seed = 5;
    auto next = [&] {
        return float((seed = seed * 6364136223846793005ull + 1) >> 40) / 16777216.f;
    };
    for (size_t i = 0; i < points.size(); ++i)
        points[i] = Vec3f(next(), next(), next()), radii[i] = 0.001f + 0.001f * next();
    Context ctx;
    const CellIndex full = buildCellIndex(points.data(), radii.data(), points.size(), 0.05, ctx);
    const size_t n = full.size();
    for (int pattern = 0; pattern < 5; ++pattern) {
        std::vector<uint8_t> keep(n, 1);
        if (pattern == 0) keep[3] = keep[70000] = keep[n - 1] = 0; // a few, early and late
        if (pattern == 1) keep[0] = 0;                             // one
        if (pattern == 2)                                          // a whole cell
            for (uint32_t i = full.starts[7]; i < full.starts[8]; ++i)
                keep[i] = 0;
        if (pattern == 3)
            for (size_t i = 0; i < n; i += 3)
                keep[i] = 0; // many: one thread
        // pattern 4: none dropped
        std::vector<Vec3f> positions;
        std::vector<uint32_t> order;
        std::vector<float> r;
        std::vector<uint64_t> keys;
        std::vector<uint32_t> starts;
        for (size_t c = 0; c < full.keys.size(); ++c) {
            const size_t before = positions.size();
            for (uint32_t i = full.starts[c]; i < full.starts[c + 1]; ++i)
                if (keep[i])
                    positions.push_back(full.positions[i]), order.push_back(full.order[i]),
                        r.push_back(full.radii[i]);
            if (positions.size() > before)
                keys.push_back(full.keys[c]), starts.push_back(uint32_t(before));
        }
        starts.push_back(uint32_t(positions.size()));
        CellIndex sub = full;
        keepParticles(sub, keep);
        ASSERT_EQ(sub.size(), positions.size()) << pattern;
        EXPECT_TRUE(std::equal(
            positions.begin(), positions.end(), sub.positions.begin(),
            [](const Vec3f& a, const Vec3f& b) { return a.x == b.x && a.y == b.y && a.z == b.z; }))
            << pattern;
        EXPECT_TRUE(std::equal(order.begin(), order.end(), sub.order.begin())) << pattern;
        EXPECT_TRUE(std::equal(r.begin(), r.end(), sub.radii.begin())) << pattern;
        ASSERT_EQ(sub.keys.size(), keys.size()) << pattern;
        EXPECT_TRUE(std::equal(keys.begin(), keys.end(), sub.keys.begin())) << pattern;
        ASSERT_EQ(sub.starts.size(), starts.size()) << pattern;
        EXPECT_TRUE(std::equal(starts.begin(), starts.end(), sub.starts.begin())) << pattern;
        for (size_t c = 0; c < sub.keys.size(); ++c) { // and each cell found by its key
            const uint64_t k = sub.keys[c];
            uint32_t xyz[3] = {0, 0, 0};
            for (int b = 0; b < 21; ++b)
                for (int a = 0; a < 3; ++a)
                    xyz[a] |= uint32_t(k >> (3 * b + a) & 1) << b;
            const CellRange found = sub.find(xyz[0], xyz[1], xyz[2]);
            ASSERT_EQ(found.begin, sub.starts[c]) << pattern << ", cell " << c;
        }
    }
}
