// LevelSet.cc - finishing and writing level sets.
#include "levelset/LevelSet.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Version.h>
#include <fluidsurf/io/AtomicFile.h>

#include <openvdb/tools/Prune.h>
#include <openvdb/tools/SignedFloodFill.h>
#include <openvdb/tree/LeafManager.h>

#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <vector>

namespace fluidsurf {
namespace levelset {

namespace {
void deactivateOutsideBand(openvdb::FloatTree& tree, float background)
{
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(tree);
    leaves.foreach ([background](openvdb::FloatTree::LeafNodeType& leaf, size_t) {
        for (auto v = leaf.beginValueOn(); v; ++v)
            if (std::abs(*v) >= background) v.setValueOff();
    });
}
} // namespace

openvdb::FloatGrid::Ptr finishLevelSet(openvdb::FloatTree::Ptr tree, const Params& params,
                                       bool keepOnlyBand, const GridInfo& info)
{
    const float background = float(params.background());
    if (keepOnlyBand) deactivateOutsideBand(*tree, background);
    openvdb::tools::signedFloodFill(*tree);
    openvdb::tools::pruneLevelSet(*tree);
    auto grid = openvdb::FloatGrid::create(tree);
    grid->setTransform(openvdb::math::Transform::createLinearTransform(params.voxelSize));
    grid->setGridClass(openvdb::GRID_LEVEL_SET);
    grid->setName("surface");
    grid->insertMeta("fluidsurf:particle_radius", openvdb::DoubleMetadata(params.radius));
    grid->insertMeta("fluidsurf:influence_radius", openvdb::DoubleMetadata(params.influenceRadius));
    grid->insertMeta("fluidsurf:smoothing_length", openvdb::DoubleMetadata(params.smoothingLength));
    grid->insertMeta("fluidsurf:t_low", openvdb::DoubleMetadata(params.tLow));
    grid->insertMeta("fluidsurf:t_high", openvdb::DoubleMetadata(params.tHigh));
    grid->insertMeta("fluidsurf:field", openvdb::StringMetadata(fieldName(params.field)));
    grid->insertMeta("fluidsurf:method", openvdb::StringMetadata(methodName(params.method)));
    grid->insertMeta("fluidsurf:particle_count", openvdb::Int64Metadata(int64_t(info.particles)));
    grid->insertMeta("fluidsurf:isolated_particles",
                     openvdb::Int64Metadata(int64_t(info.isolated)));
    grid->insertMeta("fluidsurf:source", openvdb::StringMetadata(info.source));
    grid->insertMeta("fluidsurf:version", openvdb::StringMetadata(FLUIDSURF_VERSION_STRING));
    return grid;
}

} // namespace levelset

std::vector<std::string> levelSetMetadataNames()
{
    return {
        "fluidsurf:particle_radius", "fluidsurf:influence_radius", "fluidsurf:smoothing_length",
        "fluidsurf:t_low",           "fluidsurf:t_high",           "fluidsurf:field",
        "fluidsurf:method",          "fluidsurf:particle_count",   "fluidsurf:isolated_particles",
        "fluidsurf:source",          "fluidsurf:version"};
}

namespace {
// OpenVDB's file header: magic (8 bytes), file version, library major and minor (4 each), the
// grid-offsets flag (1), then a random UUID as 36 characters. The UUID only identifies a file
// for caches, so a hash of the content serves better: equal grids give equal bytes.
constexpr size_t kUuidOffset = 8 + 4 + 4 + 4 + 1, kUuidLength = 36;

void makeUuidDeterministic(const std::string& path)
{
    std::ifstream in(path, std::ios::binary);
    std::vector<char> bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (!in.eof() && in.fail()) throw OutputError(path + ": cannot read back the written file");
    in.close();
    if (bytes.size() < kUuidOffset + kUuidLength || bytes[kUuidOffset + 8] != '-' ||
        bytes[kUuidOffset + 13] != '-')
        throw OutputError(path + ": unexpected VDB header layout (OpenVDB version?)");
    uint64_t h[2] = {0xcbf29ce484222325ull, 0x84222325cbf29ce4ull}; // two FNV-1a streams
    for (size_t i = kUuidOffset + kUuidLength; i < bytes.size(); ++i) {
        h[0] = (h[0] ^ uint8_t(bytes[i])) * 0x100000001b3ull;
        h[1] = (h[1] ^ uint8_t(bytes[i]) ^ 0x5a) * 0x100000001b3ull;
    }
    char uuid[40];
    std::snprintf(uuid, sizeof(uuid), "%08x-%04x-%04x-%04x-%012llx", unsigned(h[0] >> 32),
                  unsigned(h[0] >> 16) & 0xffff, (unsigned(h[0]) & 0x0fff) | 0x4000,
                  (unsigned(h[1] >> 48) & 0x3fff) | 0x8000,
                  (unsigned long long)(h[1] & 0xffffffffffffull));
    std::fstream out(path, std::ios::binary | std::ios::in | std::ios::out);
    out.seekp(std::streamoff(kUuidOffset));
    out.write(uuid, kUuidLength);
    if (!out) throw OutputError(path + ": cannot write the file header");
}
} // namespace

void writeLevelSet(const openvdb::GridPtrVec& grids, const std::string& path)
{
    openvdb::initialize();
    io::AtomicFile out(path);
    try {
        openvdb::io::File file(out.tempPath());
        file.setCompression(openvdb::io::COMPRESS_BLOSC | openvdb::io::COMPRESS_ACTIVE_MASK);
        file.write(grids);
        file.close();
    } catch (const openvdb::Exception& e) {
        throw OutputError(path + ": " + e.what());
    }
    makeUuidDeterministic(out.tempPath());
    out.commit();
}

} // namespace fluidsurf
