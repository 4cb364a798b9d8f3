// The Z-order cell index: keys, ranges and lookups against direct computation.
#include "neighbors/CellIndex.h"

#include <fluidsurf/Error.h>

#include <gtest/gtest.h>

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
