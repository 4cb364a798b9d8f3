// The Z-order cell index: keys, ranges and lookups against direct computation.
#include "neighbors/CellIndex.h"

#include <fluidsurf/Error.h>

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <set>

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
    pts.emplace_back(1000.f, 0.f, -7.f); // far away: sparse, not a dense box
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
