// VdbPointBuffersTest.cc - the walk of point grids' leaf buffers (io/VdbPointBuffers): point
// grids of every kind OpenVDB writes (codecs, groups, strided, uniform and transient arrays,
// pages shared by many leaves and arrays with a page of their own, leaves with descriptors of
// their own) read back array for array; corrupt ones read or are one InputError, never an abort.
#include "io/VdbGrids.h"
#include "unit/io/VdbTestFiles.h"

#include <fluidsurf/Error.h>

#include <openvdb/points/PointAttribute.h>
#include <openvdb/points/PointConversion.h>
#include <openvdb/points/PointDataGrid.h>
#include <openvdb/points/PointGroup.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace fluidsurf {
namespace {

using test::Bytes;
using test::writeVdb;
namespace pts = openvdb::points;
using openvdb::Vec3f;

struct PointScene
{
    pts::PointDataGrid::Ptr grid;
    size_t clusterPoints = 0;
};

/// n points: half in one voxel (a leaf whose wide arrays outgrow a 1 MiB page), the rest spread
/// over a cube of half-width extent (leaves are 0.4 wide), with attributes of every codec
/// OpenVDB registers.
PointScene pointScene(size_t n, float extent)
{
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> u(-1.0f, 1.0f), unit(0.0f, 1.0f);
    std::vector<Vec3f> position(n), velocity(n), colour(n), normal(n);
    std::vector<float> density(n), four(4 * n);
    std::vector<int32_t> id(n);
    std::vector<short> splash(n);
    for (size_t i = 0; i < n; ++i) {
        // all in the positive octant: one root child, whose masks take 9 KB
        const Vec3f p = extent * Vec3f(u(rng), u(rng), u(rng));
        position[i] = i % 2 ? p + Vec3f(extent + 0.01f) : Vec3f(0.01f) + 0.004f * p;
        velocity[i] = 3.0f * Vec3f(u(rng), u(rng), u(rng));
        colour[i] = Vec3f(unit(rng), unit(rng), unit(rng));
        normal[i] = (p + Vec3f(1e-3f)).unit();
        density[i] = 1000.0f + 10.0f * u(rng);
        for (int c = 0; c < 4; ++c)
            four[4 * i + size_t(c)] = float(i) + 0.25f * float(c);
        id[i] = int32_t(i * 7);
        splash[i] = short(i % 3 == 0);
    }
    const auto transform = openvdb::math::Transform::createLinearTransform(0.05);
    const pts::PointAttributeVector<Vec3f> positions(position);
    const auto index =
        openvdb::tools::createPointIndexGrid<openvdb::tools::PointIndexGrid>(positions, *transform);
    PointScene s;
    s.grid =
        pts::createPointDataGrid<pts::NullCodec, pts::PointDataGrid>(*index, positions, *transform);
    s.grid->setName("points");
    auto& tree = s.grid->tree();
    const auto& indexTree = index->tree();
    pts::appendAttribute<Vec3f>(tree, "v");
    pts::populateAttribute(tree, indexTree, "v", pts::PointAttributeVector<Vec3f>(velocity));
    pts::appendAttribute<float, pts::TruncateCodec>(tree, "density");
    pts::populateAttribute(tree, indexTree, "density", pts::PointAttributeVector<float>(density));
    pts::appendAttribute<int32_t>(tree, "id");
    pts::populateAttribute(tree, indexTree, "id", pts::PointAttributeVector<int32_t>(id));
    pts::appendAttribute<Vec3f, pts::FixedPointCodec<true, pts::UnitRange>>(tree, "Cd");
    pts::populateAttribute(tree, indexTree, "Cd", pts::PointAttributeVector<Vec3f>(colour));
    pts::appendAttribute<Vec3f, pts::UnitVecCodec>(tree, "N");
    pts::populateAttribute(tree, indexTree, "N", pts::PointAttributeVector<Vec3f>(normal));
    pts::appendAttribute<float>(tree, "pscale", 0.5f); // never set: a uniform array per leaf
    // transient (kept in memory, never written) between written ones, and again at the end
    pts::appendAttribute<float>(tree, "early", 1.0f, 1, true, nullptr, false, true);
    pts::appendAttribute<float>(tree, "four", 0.0f, 4);
    pts::populateAttribute(tree, indexTree, "four", pts::PointAttributeVector<float>(four, 4), 4);
    pts::appendGroup(tree, "splash");
    pts::setGroup(tree, indexTree, splash, "splash");
    pts::appendAttribute<float>(tree, "scratch", 1.0f, 1, true, nullptr, false, true);
    s.clusterPoints = n / 2;
    return s;
}

/// Every leaf of b equals a's at the same origin: voxel offsets, and every array of a but the
/// transient ones, with the same type, size, stride and stored bytes; groups alike.
void expectSamePoints(const pts::PointDataGrid& a, const openvdb::GridBase::Ptr& readBack)
{
    const auto b = openvdb::gridPtrCast<pts::PointDataGrid>(readBack);
    ASSERT_TRUE(b);
    EXPECT_EQ(a.tree().leafCount(), b->tree().leafCount());
    for (auto leaf = a.tree().cbeginLeaf(); leaf; ++leaf) {
        const auto* other = b->tree().probeConstLeaf(leaf->origin());
        ASSERT_TRUE(other) << leaf->origin();
        for (openvdb::Index v = 0; v < leaf->SIZE; ++v)
            ASSERT_EQ(leaf->getValue(v), other->getValue(v));
        EXPECT_EQ(leaf->getValueMask(), other->getValueMask());
        const auto& set = leaf->attributeSet();
        const auto& otherSet = other->attributeSet();
        size_t written = 0;
        for (const auto& [name, pos] : set.descriptor().map()) {
            const pts::AttributeArray* array = set.getConst(pos);
            if (array->isTransient()) {
                EXPECT_EQ(otherSet.find(name), pts::AttributeSet::INVALID_POS) << name;
                continue;
            }
            ++written;
            const size_t otherPos = otherSet.find(name);
            ASSERT_NE(otherPos, pts::AttributeSet::INVALID_POS) << name;
            EXPECT_TRUE(*array == *otherSet.getConst(otherPos)) << name;
        }
        EXPECT_EQ(otherSet.size(), written);
        EXPECT_EQ(set.descriptor().groupMap(), otherSet.descriptor().groupMap());
    }
}

/// grid written by OpenVDB with this compression, read through the walk, equals grid.
void expectReadsBack(const pts::PointDataGrid::Ptr& grid, uint32_t compression, bool file)
{
    SCOPED_TRACE("compression " + std::to_string(compression) + (file ? " file" : " stream"));
    const Bytes bytes = writeVdb({grid}, compression, file);
    const openvdb::GridPtrVecPtr grids =
        io_internal::readVdbGrids(bytes.data(), bytes.size(), "p.vdb");
    ASSERT_EQ(grids->size(), 1u);
    expectSamePoints(*grid, (*grids)[0]);
}

TEST(VdbPointBuffers, EveryKindOfPointGridOpenVdbWritesReadsBackExactly)
{
    openvdb::initialize();
    const PointScene scene = pointScene(160000, 1.0f);
    // the cluster leaf's 'four' takes 80,000 x 16 bytes: more than a page, so a page of its own
    const auto* cluster = scene.grid->tree().probeConstLeaf(openvdb::Coord(0));
    ASSERT_TRUE(cluster);
    ASSERT_GT(cluster->pointCount(), 1024u * 1024u / 16u);
    using namespace openvdb::io;
    for (uint32_t compression :
         {uint32_t(COMPRESS_NONE), uint32_t(COMPRESS_ZIP | COMPRESS_ACTIVE_MASK),
          uint32_t(COMPRESS_BLOSC | COMPRESS_ACTIVE_MASK), uint32_t(COMPRESS_BLOSC)})
        for (bool file : {false, true})
            expectReadsBack(scene.grid, compression, file);
}

TEST(VdbPointBuffers, LeavesWithDescriptorsOfTheirOwnReadBack)
{
    // a leaf taken from another grid keeps that grid's descriptor: OpenVDB then writes one
    // descriptor per leaf instead of a shared one (header byte 0)
    openvdb::initialize();
    const PointScene scene = pointScene(2000, 1.0f);
    const auto plain = pts::createPointDataGrid<pts::NullCodec, pts::PointDataGrid>(
        std::vector<Vec3f>{Vec3f(100.0f), Vec3f(100.1f)},
        *openvdb::math::Transform::createLinearTransform(0.05));
    scene.grid->tree().addLeaf(new pts::PointDataTree::LeafNodeType(*plain->tree().cbeginLeaf()));
    for (uint32_t compression :
         {uint32_t(openvdb::io::COMPRESS_BLOSC), uint32_t(openvdb::io::COMPRESS_ZIP)})
        expectReadsBack(scene.grid, compression, true);
}

TEST(VdbPointBuffers, ArrayPastItsPageIsRefusedBeforeOpenVdbReadsPastIt)
{
    // one page holds attribute 'id' of every leaf; a page header promising 2 bytes less makes
    // OpenVDB copy the last leaf's array from past the end of the page's buffer (with a leaf
    // after it, OpenVDB's PagedInputStream would assert: an abort)
    openvdb::initialize();
    auto grid = pts::createPointDataGrid<pts::NullCodec, pts::PointDataGrid>(
        std::vector<Vec3f>{Vec3f(0.0f), Vec3f(1.0f), Vec3f(2.0f), Vec3f(3.0f)},
        *openvdb::math::Transform::createLinearTransform(0.05));
    pts::appendAttribute<int32_t>(grid->tree(), "id", 5); // uniform: not compressed
    const size_t leaves = grid->tree().leafCount();
    ASSERT_EQ(leaves, 4u);
    std::vector<pts::PointDataTree::LeafNodeType*> all;
    grid->tree().getNodes(all);
    for (auto* leaf : all) // one non-uniform value per leaf: 4 bytes, all in one page
        leaf->attributeArray("id").expand();
    const Bytes good = writeVdb({grid}, openvdb::io::COMPRESS_BLOSC, true);
    EXPECT_NO_THROW(io_internal::readVdbGrids(good.data(), good.size(), "p.vdb"));
    // the page headers, one per attribute, back to back: 'P' raw (-48: four arrays of 12
    // bytes), then 'id' raw (-16: four arrays of 4); 'id' made to say 14
    Bytes bad = good;
    bool patched = false;
    for (size_t i = 0; i + 8 <= bad.size() && !patched; ++i) {
        int32_t p, id;
        std::memcpy(&p, &bad[i], 4);
        std::memcpy(&id, &bad[i + 4], 4);
        if (p == -48 && id == -16) {
            const int32_t shorter = -14;
            std::memcpy(&bad[i + 4], &shorter, 4);
            patched = true;
        }
    }
    ASSERT_TRUE(patched);
    try {
        io_internal::readVdbGrids(bad.data(), bad.size(), "p.vdb");
        FAIL() << "read an array past its page";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("runs past its page"), std::string::npos) << e.what();
    }
}

/// Bytes of a small point grid flipped whole and in their lowest bit, random flips of a few
/// bytes, and every fifth cut: the read either succeeds or throws one InputError. An abort or
/// a crash ends the test binary; ASan builds (tools/fuzz) also catch reads out of bounds.
TEST(VdbPointBuffers, EveryByteCorruptedReadsOrIsOneInputError)
{
    openvdb::initialize();
    const PointScene scene = pointScene(60, 0.3f);
    const Bytes good = writeVdb({scene.grid}, openvdb::io::COMPRESS_BLOSC, true);
    test::ReadOrRefuse attempt;
    // the leaf buffers (the last 7 KB of 16) byte by byte; the topology before them, which
    // VdbCheckTest covers on level sets, every fourth byte
    const size_t buffers = good.size() - std::min<size_t>(good.size(), 7000);
    for (size_t i = 0; i < good.size(); i += i < buffers ? 4 : 1)
        for (uint8_t value : {uint8_t(good[i] ^ 0xff), uint8_t(good[i] ^ 0x01)}) {
            Bytes b = good;
            b[i] = value;
            attempt(b);
        }
    std::mt19937 rng(12);
    for (int k = 0; k < 2000; ++k) {
        Bytes b = good;
        for (int f = 1 + int(rng() % 4); f > 0; --f)
            b[rng() % b.size()] ^= uint8_t(1 + rng() % 255);
        attempt(b);
    }
    for (size_t n = 0; n < good.size(); n += 5)
        attempt(Bytes(good.begin(), good.begin() + long(n)));
    EXPECT_GT(attempt.refused, attempt.read);
    EXPECT_GT(attempt.read, 0u);
}

} // namespace
} // namespace fluidsurf
