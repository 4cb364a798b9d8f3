// Band completion (field/CompleteBand.h) against a brute-force reading of its rule: every
// inactive axis neighbour of an active voxel with |phi| < 0.5 voxel, and every inactive corner of
// the 4 cells around an edge with a sign change between active voxels, is added and evaluated,
// until nothing is added. The reference walks every voxel and all 6 neighbours with plain
// coordinate lookups (no leaf bit masks), over a std::map, so it shares nothing with the stage.
#include "field/CompleteBand.h"

#include <gtest/gtest.h>

#include <cmath>
#include <map>

using namespace fluidsurf;

namespace {

using Voxels = std::map<openvdb::Coord, float>;

/// A wavy sphere's signed distance, in voxels (voxel size 1): crossings at every orientation,
/// and across leaf faces.
float phi(const openvdb::Coord& c)
{
    const double x = c.x() - 3.3, y = c.y() + 1.7, z = c.z() - 0.6;
    const double r = std::sqrt(x * x + y * y + z * z);
    return float(r - 13.0 - 1.5 * std::sin(0.5 * x) * std::cos(0.4 * y));
}

/// The incomplete band: |phi| < 2.5 voxels where x + y < 4, and only |phi| < 0.6 elsewhere,
/// so that crossings reach the band's edge there; a few voxels dropped inside as holes.
Voxels startBand()
{
    Voxels band;
    for (int x = -24; x <= 24; ++x)
        for (int y = -24; y <= 24; ++y)
            for (int z = -24; z <= 24; ++z) {
                const openvdb::Coord c(x, y, z);
                const float v = phi(c);
                const bool hole = (x * 7 + y * 3 + z) % 23 == 0;
                if (!hole && std::abs(v) < (x + y < 4 ? 2.5f : 0.6f)) band[c] = v;
            }
    return band;
}

/// The rule, until nothing is added, new voxels valued by `value`. `tile`: voxels read as active
/// with this value (an active tile of the tree), never added.
Voxels referenceComplete(Voxels band, const std::map<openvdb::Coord, float>& tile,
                         float (*value)(const openvdb::Coord&) = phi)
{
    auto find = [&](const openvdb::Coord& c, float& v) {
        if (auto it = band.find(c); it != band.end()) return v = it->second, true;
        if (auto it = tile.find(c); it != tile.end()) return v = it->second, true;
        return false;
    };
    for (;;) {
        std::map<openvdb::Coord, bool> add;
        for (const auto& [c, v] : band)
            for (int axis = 0; axis < 3; ++axis)
                for (int step : {-1, 1}) {
                    openvdb::Coord n = c;
                    n[axis] += step;
                    float w;
                    if (!find(n, w)) {
                        if (std::abs(v) < 0.5f) add[n] = true;
                    } else if ((w < 0) != (v < 0)) {
                        const openvdb::Coord low = step == 1 ? c : n;
                        const int b = (axis + 1) % 3, d = (axis + 2) % 3;
                        for (int i = 0; i <= 1; ++i)
                            for (int j = -1; j <= 1; ++j)
                                for (int k = -1; k <= 1; ++k) {
                                    openvdb::Coord m = low;
                                    m[axis] += i, m[b] += j, m[d] += k;
                                    float unused;
                                    if (!find(m, unused)) add[m] = true;
                                }
                    }
                }
        if (add.empty()) return band;
        for (const auto& [c, unused] : add)
            band[c] = value(c);
    }
}

/// The stage on `band` (plus an active leaf-sized tile of value -1 at tileOrigin, if given):
/// the voxels active in leaves afterwards.
Voxels runStage(const Voxels& band, float (*value)(const openvdb::Coord&) = phi,
                const openvdb::Coord* tileOrigin = nullptr)
{
    openvdb::FloatTree tree(1e3f);
    if (tileOrigin) {
        tree.addTile(1, *tileOrigin, -1.f, true);
        EXPECT_EQ(tree.activeTileCount(), 1u);
    }
    for (const auto& [c, v] : band)
        tree.setValueOn(c, v);
    Level level;
    level.voxelSize = 1;
    Context ctx;
    const size_t added = field::completeBand(
        tree, level,
        [value](openvdb::FloatTree& grown) {
            for (auto it = grown.beginValueOn(); it; ++it)
                it.setValue(value(it.getCoord()));
        },
        ctx);
    Voxels out;
    for (auto it = tree.cbeginLeaf(); it; ++it)
        for (auto v = it->cbeginValueOn(); v; ++v)
            out[v.getCoord()] = *v;
    EXPECT_EQ(added, out.size() - band.size());
    return out;
}

void expectSame(const Voxels& expected, const Voxels& got)
{
    ASSERT_EQ(got.size(), expected.size());
    for (const auto& [c, v] : expected) {
        const auto it = got.find(c);
        ASSERT_TRUE(it != got.end()) << "missing " << c;
        EXPECT_EQ(it->second, v) << c;
    }
}

} // namespace

TEST(CompleteBand, AddsWhatTheRuleAddsAndNothingElse)
{
    const Voxels band = startBand();
    const Voxels expected = referenceComplete(band, {});
    ASSERT_GT(expected.size(), band.size() + 1000); // the test has something to complete
    expectSame(expected, runStage(band));
}

TEST(CompleteBand, EachLoneCrossingGetsItsCellsAtEveryPlaceInALeaf)
{
    // One pair of active voxels per leaf, leaves 2 apart so that nothing overlaps: its edge along
    // each axis, its low end at every corner-or-face place of the leaf (0, 1, 6, 7 per axis),
    // with a sign change far from zero (only the 18 corners), near zero (the neighbours too) or
    // without one. Nothing else in the band adds those voxels, so each pair shows whether the
    // stage read its edge, within the leaf or across a face.
    const int places[4] = {0, 1, 6, 7};
    const float values[4][2] = {{0.7f, -0.7f}, {-0.3f, 0.3f}, {0.2f, -0.9f}, {0.7f, 0.9f}};
    Voxels band;
    int leaf = 0;
    for (int axis = 0; axis < 3; ++axis)
        for (int px : places)
            for (int py : places)
                for (int pz : places)
                    for (const auto& v : values) {
                        const openvdb::Coord origin(16 * (leaf % 12), 16 * (leaf / 12 % 12),
                                                    16 * (leaf / 144) - 64);
                        ++leaf;
                        const openvdb::Coord low = origin + openvdb::Coord(px, py, pz);
                        openvdb::Coord high = low;
                        high[axis] += 1;
                        band[low] = v[0], band[high] = v[1];
                    }
    auto outside = [](const openvdb::Coord&) { return 5.f; }; // far outside: no new near voxels
    const Voxels expected = referenceComplete(band, {}, outside);
    ASSERT_GT(expected.size(), band.size() + 10000);
    expectSame(expected, runStage(band, outside));
}

TEST(CompleteBand, ReadsAnActiveTileAsActiveVoxels)
{
    // A negative active tile (an 8^3 leaf-sized one, level 1 of the tree) beside the band:
    // its voxels count as active neighbours, sign changes against it grow the band, and none
    // of its voxels is added.
    const Voxels band = startBand();
    const openvdb::Coord tileOrigin(16, -8, 0); // phi > 0 there: a sign change at its face
    std::map<openvdb::Coord, float> tile;
    for (int x = 0; x < 8; ++x)
        for (int y = 0; y < 8; ++y)
            for (int z = 0; z < 8; ++z)
                tile[tileOrigin + openvdb::Coord(x, y, z)] = -1.f;
    Voxels start;
    for (const auto& [c, v] : band)
        if (!tile.count(c)) start[c] = v;
    const Voxels expected = referenceComplete(start, tile);
    expectSame(expected, runStage(start, phi, &tileOrigin));
}
