// NarrowBandTest.cc - the band's topology (narrowband::buildNarrowBand) against a brute-force
// list of every voxel within the width of every seed, voxel by voxel, on random particles on both
// sides of the origin (leaf boxes across negative coordinates), for widths from under a voxel to
// several leaves' worth of voxels: the same active voxels, and no leaf without one.
#include "narrowband/NarrowBand.h"

#include <gtest/gtest.h>

#include <cmath>
#include <random>
#include <set>
#include <tuple>

using namespace fluidsurf;

namespace {

using Voxel = std::tuple<int, int, int>;

/// Every voxel within width of a seed, as NarrowBand.h defines it (inclusive up to 1e-6 voxel).
std::set<Voxel> bruteForce(const neighbors::CellIndex& index, const classify::Classification& c,
                           bool keepIsolated, double width, double dx)
{
    std::set<Voxel> out;
    for (size_t i = 0; i < index.size(); ++i) {
        const uint8_t k = c.classes[i];
        if (!(classify::isSurface(k) || (keepIsolated && k == classify::Isolated))) continue;
        const Vec3f& p = index.positions[i];
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            lo[a] = int(std::ceil((p[a] - width) / dx - 1e-6));
            hi[a] = int(std::floor((p[a] + width) / dx + 1e-6));
        }
        for (int x = lo[0]; x <= hi[0]; ++x)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int z = lo[2]; z <= hi[2]; ++z)
                    out.insert({x, y, z});
    }
    return out;
}

} // namespace

TEST(NarrowBand, EveryVoxelWithinTheWidthOfASeedAndNoOther)
{
    std::mt19937 rng(23);
    std::uniform_real_distribution<float> coord(-0.3f, 0.25f);
    Context ctx;
    const double dx = 0.01;
    for (const double width : {0.004, 0.01, 0.023, 0.081}) // under a voxel to over a leaf
        for (const bool keepIsolated : {false, true}) {
            std::vector<Vec3f> points(3000);
            for (Vec3f& p : points)
                p = Vec3f(coord(rng), coord(rng), coord(rng));
            const neighbors::CellIndex index =
                neighbors::buildCellIndex(points.data(), nullptr, points.size(), 0.05, ctx);
            classify::Classification c;
            c.classes.resize(index.size());
            for (size_t i = 0; i < index.size(); ++i)
                c.classes[i] = uint8_t(rng() % 4); // interior, surface, splash, isolated
            Params params;
            params.keepIsolated = keepIsolated;
            Level level;
            level.voxelSize = dx;
            const openvdb::MaskTree::Ptr band =
                narrowband::buildNarrowBand(index, c, params, level, width, ctx);
            const std::set<Voxel> expected = bruteForce(index, c, keepIsolated, width, dx);
            std::set<Voxel> got;
            for (auto it = band->cbeginValueOn(); it; ++it) {
                const openvdb::Coord ijk = it.getCoord();
                got.insert({ijk.x(), ijk.y(), ijk.z()});
            }
            EXPECT_EQ(got.size(), expected.size()) << "width " << width;
            EXPECT_TRUE(got == expected) << "width " << width << ", isolated " << keepIsolated;
            std::set<Voxel> leaves;
            for (const Voxel& v : expected)
                leaves.insert({std::get<0>(v) & ~7, std::get<1>(v) & ~7, std::get<2>(v) & ~7});
            EXPECT_EQ(band->leafCount(), leaves.size()) << "width " << width;
        }
}
