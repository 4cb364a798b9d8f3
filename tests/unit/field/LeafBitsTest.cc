// A leaf's voxels as bits (field/LeafBits.h) against voxel-by-voxel brute force on random leaves:
// the active shell and the full 18-corner stencils per axis, with the 26 neighbour leaves there,
// missing or tiles, and the frontier candidates per direction, with neighbours in the 6 adjacent
// leaves, a missing neighbour leaf, and an active tile.
#include "field/LeafBits.h"

#include <gtest/gtest.h>

#include <random>

using namespace fluidsurf;
using namespace fluidsurf::field;

namespace {

bool bitOf(const Words& w, const openvdb::Coord& l)
{
    return w[l.x()] >> (l.y() * 8 + l.z()) & 1;
}

} // namespace

TEST(LeafBits, EdgeStencilsCountTheNeighbourLeaves)
{
    // A 3x3x3 block of leaves, 97% of the voxels active (so that many stencils are full, many
    // one corner short), then each of the 26 neighbour leaves kept, left out, or made an active
    // or an inactive tile; the shell and the stencils against isValueOn voxel by voxel.
    std::mt19937 rng(7);
    const openvdb::Coord centre(-16, 8, 24);
    std::bernoulli_distribution on(0.97);
    std::uniform_int_distribution<int> fate(0, 7);
    for (int trial = 0; trial < 12; ++trial) {
        openvdb::FloatTree tree(2.f);
        for (int x = -8; x < 16; ++x)
            for (int y = -8; y < 16; ++y)
                for (int z = -8; z < 16; ++z)
                    if (on(rng)) tree.setValueOn(centre + openvdb::Coord(x, y, z), 0.5f);
        for (int dx = -1; dx <= 1; ++dx)
            for (int dy = -1; dy <= 1; ++dy)
                for (int dz = -1; dz <= 1; ++dz) {
                    if (!dx && !dy && !dz) continue;
                    const openvdb::Coord o = centre + openvdb::Coord(8 * dx, 8 * dy, 8 * dz);
                    const int f = trial == 0 ? 0 : fate(rng); // the first trial keeps them all
                    if (f >= 4) continue;                     // kept
                    delete tree.stealNode<FloatLeaf>(o, 2.f, false);
                    if (f == 2) tree.addTile(1, o, -0.25f, true);
                    if (f == 3) tree.addTile(1, o, 2.f, false);
                }
        const FloatLeaf* home = tree.probeConstLeaf(centre);
        ASSERT_NE(home, nullptr);
        openvdb::tree::ValueAccessor<const openvdb::FloatTree> acc(tree);
        const ActiveShell shell = activeShell(*home, acc);
        auto active = [&](const openvdb::Coord& l) { return tree.isValueOn(centre + l); };
        for (int x = -1; x <= 8; ++x)
            for (int y = -1; y <= 8; ++y)
                for (int z = -1; z <= 8; ++z)
                    ASSERT_EQ(bool(shell.rows[x + 1][y + 1] >> (z + 1) & 1),
                              active(openvdb::Coord(x, y, z)))
                        << openvdb::Coord(x, y, z) << " trial " << trial;
        const EdgeStencils e = edgeStencils(shell);
        auto full = [&](const openvdb::Coord& c, int axis) {
            const int b = (axis + 1) % 3, d = (axis + 2) % 3;
            bool all = true;
            for (int i = 0; i <= 1; ++i)
                for (int j = -1; j <= 1; ++j)
                    for (int k = -1; k <= 1; ++k) {
                        openvdb::Coord m = c;
                        m[axis] += i, m[b] += j, m[d] += k;
                        all = all && active(m);
                    }
            return all;
        };
        size_t fullEdges = 0;
        for (int axis = 0; axis < 3; ++axis)
            for (int x = 0; x < 8; ++x)
                for (int y = 0; y < 8; ++y)
                    for (int z = 0; z < 8; ++z) {
                        const openvdb::Coord c(x, y, z);
                        openvdb::Coord below = c;
                        below[axis] -= 1;
                        fullEdges += full(c, axis);
                        ASSERT_EQ(bitOf(e.full[axis], c), full(c, axis))
                            << "axis " << axis << " at " << c << " trial " << trial;
                        ASSERT_EQ(bitOf(e.fullBelow[axis], c), full(below, axis))
                            << "axis " << axis << " at " << c << " trial " << trial;
                        ASSERT_EQ(bitOf(e.activeBelow[axis], c), active(below))
                            << "axis " << axis << " at " << c << " trial " << trial;
                    }
        EXPECT_GT(fullEdges, 100u); // the test tests something
    }
}

namespace {

/// A 3x3x3 block of leaves around the one at `centre`, random values in [-1, 1] and random
/// activity; `missing` (a direction index, or -1) leaves that face neighbour out; `tile` puts an
/// active tile there instead.
openvdb::FloatTree::Ptr randomBlock(std::mt19937& rng, const openvdb::Coord& centre, int missing,
                                    bool tile)
{
    auto tree = std::make_shared<openvdb::FloatTree>(2.f);
    std::uniform_real_distribution<float> value(-1.f, 1.f);
    std::bernoulli_distribution on(0.75);
    for (int x = -8; x < 16; ++x)
        for (int y = -8; y < 16; ++y)
            for (int z = -8; z < 16; ++z) {
                const openvdb::Coord c = centre + openvdb::Coord(x, y, z);
                const float v = value(rng);
                if (on(rng)) tree->setValueOn(c, v);
            }
    if (missing >= 0) {
        openvdb::Coord o = centre;
        o[missing / 2] += missing % 2 ? 8 : -8;
        delete tree->stealNode<FloatLeaf>(o, 2.f, false);
        if (tile) tree->addTile(1, o, -0.25f, true);
    }
    return tree;
}

} // namespace

TEST(LeafBits, FrontierCandidatesAreTheVoxelsWithSomethingToFind)
{
    std::mt19937 rng(11);
    const openvdb::Coord centre(-16, 8, 24);
    const float threshold = 0.5f;
    for (int missing = -1; missing < 6; ++missing)
        for (bool tile : {false, true}) {
            if (missing < 0 && tile) continue;
            auto tree = randomBlock(rng, centre, missing, tile);
            const FloatLeaf* home = tree->probeConstLeaf(centre);
            ASSERT_NE(home, nullptr);
            openvdb::tree::ValueAccessor<const openvdb::FloatTree> acc(*tree);
            const Directions got = frontierCandidates(*home, threshold, acc);
            for (int dir = 0; dir < 6; ++dir)
                for (int x = 0; x < 8; ++x)
                    for (int y = 0; y < 8; ++y)
                        for (int z = 0; z < 8; ++z) {
                            const openvdb::Coord l(x, y, z), c = centre + l;
                            float v, w;
                            const bool active = acc.probeValue(c, v);
                            openvdb::Coord n = c;
                            n[dir / 2] += dir % 2 ? 1 : -1;
                            const bool nActive = acc.probeValue(n, w);
                            bool expected = active && ((!nActive && std::abs(v) < threshold) ||
                                                       (nActive && (v < 0) != (w < 0)));
                            if (tile) expected = active; // a tile beside: every voxel is scanned
                            ASSERT_EQ(bitOf(got[dir], l), expected)
                                << "direction " << dir << " at " << l << ", missing " << missing
                                << (tile ? " (tile)" : "");
                        }
        }
}
