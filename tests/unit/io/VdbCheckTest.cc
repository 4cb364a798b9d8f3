// VdbCheckTest.cc - the walk every .vdb goes through before OpenVDB reads it (io/VdbCheck):
// valid files of every kind OpenVDB writes read back voxel for voxel; every single-byte
// corruption and every cut of a level set either reads or is one InputError, never a crash.
#include "io/VdbCheck.h"
#include "io/VdbGrids.h"
#include "unit/io/VdbTestFiles.h"

#include <fluidsurf/Error.h>

#include <openvdb/tools/LevelSetSphere.h>

#include <gtest/gtest.h>

#include <cmath>

namespace fluidsurf {
namespace {

using test::Bytes;
using test::writeVdb;

openvdb::FloatGrid::Ptr sphere()
{
    auto g = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(
        1.0f, openvdb::Vec3f(0.1f, 0.2f, 0.3f), 0.1f, 3.0f);
    g->setName("surface");
    return g;
}

template <typename T> double difference(const T& a, const T& b)
{
    return std::abs(double(a) - double(b));
}
template <typename T>
double difference(const openvdb::math::Vec3<T>& a, const openvdb::math::Vec3<T>& b)
{
    return double((a - b).length());
}

/// Same active voxels, same values (tolerance for half floats), same background.
template <typename GridT>
void expectSameGrid(const GridT& a, const openvdb::GridBase::Ptr& b, double tolerance)
{
    ASSERT_TRUE(b);
    auto g = openvdb::gridPtrCast<GridT>(b);
    ASSERT_TRUE(g) << b->getName() << " has type " << b->type();
    EXPECT_EQ(g->activeVoxelCount(), a.activeVoxelCount());
    EXPECT_EQ(g->tree().leafCount(), a.tree().leafCount());
    auto acc = g->getConstAccessor();
    size_t differ = 0;
    for (auto v = a.cbeginValueOn(); v; ++v) {
        const auto got = acc.getValue(v.getCoord());
        differ += !acc.isValueOn(v.getCoord()) || difference(got, *v) > tolerance;
    }
    EXPECT_EQ(differ, 0u) << a.getName();
}

TEST(VdbCheck, EveryKindOfGridOpenVdbWritesReadsBackExactly)
{
    openvdb::initialize();
    auto surface = sphere();
    auto half = surface->deepCopy();
    half->setName("half");
    half->setSaveFloatAsHalf(true);
    auto velocity = openvdb::Vec3SGrid::create(openvdb::Vec3s(0));
    velocity->setName("vel");
    auto ids = openvdb::Int32Grid::create(-1);
    ids->setName("id");
    auto dens = openvdb::DoubleGrid::create(0);
    dens->setName("density");
    for (auto v = surface->cbeginValueOn(); v; ++v) {
        const openvdb::Coord c = v.getCoord();
        velocity->tree().setValue(c, openvdb::Vec3s(float(c.x()), *v, 1.5f));
        ids->tree().setValue(c, c.x() * 7 + c.y());
        dens->tree().setValue(c, double(*v) * 1e-3);
    }
    ids->tree().addTile(1, openvdb::Coord(4096), 42, true); // an active tile of an internal node
    auto instance = surface->copyGrid();                    // shares the tree: written as one
    instance->setName("instance");
    auto mask = openvdb::BoolGrid::create(false); // a type the walk does not read: left out
    mask->setName("mask");
    mask->tree().setValue(openvdb::Coord(1, 2, 3), true);

    using namespace openvdb::io;
    for (uint32_t compression :
         {uint32_t(COMPRESS_NONE), uint32_t(COMPRESS_ZIP), uint32_t(COMPRESS_ACTIVE_MASK),
          uint32_t(COMPRESS_ZIP | COMPRESS_ACTIVE_MASK),
          uint32_t(COMPRESS_BLOSC | COMPRESS_ACTIVE_MASK)})
        for (bool file : {false, true}) {
            SCOPED_TRACE("compression " + std::to_string(compression) +
                         (file ? " file" : " stream"));
            // the bool grid last: without grid offsets, a grid that is not walked can only
            // be the last one (its end cannot be found)
            const Bytes bytes =
                writeVdb({surface, half, velocity, ids, dens, instance, mask}, compression, file);
            std::vector<std::string> skipped;
            const openvdb::GridPtrVecPtr grids =
                io_internal::readVdbGrids(bytes.data(), bytes.size(), "t.vdb", &skipped);
            ASSERT_EQ(grids->size(), 6u);
            expectSameGrid(*surface, (*grids)[0], 0);
            expectSameGrid(*surface, (*grids)[1], 2e-3); // half precision near |d| <= 0.3
            expectSameGrid(*velocity, (*grids)[2], 0);
            expectSameGrid(*ids, (*grids)[3], 0);
            expectSameGrid(*dens, (*grids)[4], 0);
            expectSameGrid(*surface, (*grids)[5], 0);
            EXPECT_EQ((*grids)[0]->getGridClass(), openvdb::GRID_LEVEL_SET);
            ASSERT_EQ(skipped.size(), 1u);
            EXPECT_NE(skipped[0].find("mask (Tree_bool_5_4_3)"), std::string::npos) << skipped[0];
        }
}

/// Bytes of a small level set, flipped whole and in their lowest bit, and every seventh cut: the
/// read either succeeds or throws one InputError. A crash ends the test binary; ASan builds
/// (tools/fuzz) also catch reads out of bounds that happen not to crash.
TEST(VdbCheck, EveryByteCorruptedReadsOrIsOneInputError)
{
    openvdb::initialize();
    auto g = openvdb::tools::createLevelSetSphere<openvdb::FloatGrid>(0.25f, openvdb::Vec3f(0),
                                                                      0.1f, 2.0f);
    g->setName("surface");
    for (uint32_t compression :
         {uint32_t(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK),
          uint32_t(openvdb::io::COMPRESS_ZIP | openvdb::io::COMPRESS_ACTIVE_MASK)}) {
        const Bytes good = writeVdb({g}, compression, true);
        test::ReadOrRefuse attempt;
        // every byte up to the root node's child (header, metadata, descriptor, transform,
        // root); then every 5th: the masks of a child are 9 KB of the same kind of byte
        for (size_t i = 0; i < good.size(); i += i < 1024 ? 1 : 5)
            for (uint8_t value : {uint8_t(good[i] ^ 0xff), uint8_t(good[i] ^ 0x01)}) {
                Bytes b = good;
                b[i] = value;
                attempt(b);
            }
        for (size_t n = 0; n < good.size(); n += 7)
            attempt(Bytes(good.begin(), good.begin() + long(n)));
        EXPECT_GT(attempt.refused, attempt.read); // most damage is caught; flipped values read
        EXPECT_GT(attempt.read, 0u);
    }
}

/// The last int64 equal to from (a chunk header: the leaf's chunk is the file's last) set to to.
Bytes withLastChunkSize(Bytes b, int64_t from, int64_t to)
{
    for (size_t i = b.size() - 8; i-- > 0;) {
        int64_t v;
        std::memcpy(&v, &b[i], 8);
        if (v == from) {
            std::memcpy(&b[i], &to, 8);
            return b;
        }
    }
    ADD_FAILURE() << "no chunk of " << from << " bytes";
    return b;
}

TEST(VdbCheck, RawChunkLongerThanItsNodeIsRefusedBeforeOpenVdbCopiesIt)
{
    // OpenVDB's blosc reader copies a raw chunk of the length the file gives into a buffer of
    // the node's size, and only then compares the two (a heap overflow)
    openvdb::initialize();
    auto g = openvdb::FloatGrid::create(3.0f);
    g->tree().setValue(openvdb::Coord(0), 1.0f); // one leaf with one active value
    // with active-mask compression the leaf stores that one float: a blosc chunk of 16 + 4
    // bytes, made to say "64 raw bytes follow"
    const Bytes good =
        writeVdb({g}, openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK, true);
    const Bytes bad = withLastChunkSize(good, 20, -64);
    try {
        io_internal::readVdbGrids(bad.data(), bad.size(), "c.vdb");
        FAIL() << "read a chunk longer than its leaf";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("a raw chunk of 64 bytes where 4 are needed"),
                  std::string::npos)
            << e.what();
    }
}

TEST(VdbCheck, OffsetsMustMatchTheGridsRealEnd)
{
    openvdb::initialize();
    const Bytes good = writeVdb({sphere()}, openvdb::io::COMPRESS_BLOSC, true);
    // the end offset is the third int64 after the descriptor strings; find it by value
    const int64_t end = int64_t(good.size());
    Bytes bad = good;
    for (size_t i = 0; i + 8 <= bad.size(); ++i) {
        int64_t v;
        std::memcpy(&v, &bad[i], 8);
        if (v == end) {
            const int64_t shorter = end - 100;
            std::memcpy(&bad[i], &shorter, 8);
            break;
        }
    }
    EXPECT_THROW(io_internal::readVdbGrids(bad.data(), bad.size(), "c.vdb"), InputError);
    EXPECT_NO_THROW(io_internal::readVdbGrids(good.data(), good.size(), "c.vdb"));
}

} // namespace
} // namespace fluidsurf
