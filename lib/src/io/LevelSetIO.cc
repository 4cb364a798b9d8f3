// LevelSetIO.cc - level sets in .vdb files: read (validated like every reader), written
// atomically with a content-derived UUID, and described for `fluidsurf info`.
#include <fluidsurf/Error.h>
#include <fluidsurf/io/AtomicFile.h>
#include <fluidsurf/io/LevelSetIO.h>

#include "io/FileBuffer.h"
#include "io/VdbGrids.h"

#include <cmath>
#include <cstdio>
#include <fstream>
#include <iterator>
#include <vector>

namespace fluidsurf {
namespace io {

openvdb::FloatGrid::Ptr readLevelSet(const std::string& path, const std::string& gridName)
{
    const std::vector<uint8_t> bytes = io_internal::readFile(path);
    return readLevelSetFromMemory(bytes.data(), bytes.size(), path, gridName);
}

namespace {

/// The grid to mesh among grids (see readLevelSet).
openvdb::FloatGrid::Ptr pickLevelSet(const openvdb::GridPtrVec& grids, const std::string& path,
                                     const std::string& gridName)
{
    openvdb::FloatGrid::Ptr levelSet, anyFloat;
    std::string names;
    for (const openvdb::GridBase::Ptr& g : grids) {
        names += (names.empty() ? "" : ", ") + g->getName() + " (" + g->valueType() + ", " +
                 openvdb::GridBase::gridClassToString(g->getGridClass()) + ")";
        auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
        if (!f) continue;
        if (!gridName.empty()) {
            if (f->getName() == gridName && !levelSet) levelSet = f;
            continue;
        }
        if (!levelSet && f->getGridClass() == openvdb::GRID_LEVEL_SET) levelSet = f;
        if (!anyFloat) anyFloat = f;
    }
    if (!levelSet) levelSet = gridName.empty() ? anyFloat : nullptr;
    if (!levelSet)
        throw InputError(
            path + ": no " +
            (gridName.empty() ? std::string("float grid") : "float grid named '" + gridName + "'") +
            " in this VDB (grids: " + (names.empty() ? std::string("none") : names) + ")");
    const openvdb::Vec3d voxel = levelSet->voxelSize();
    for (int a = 0; a < 3; ++a)
        if (!(std::isfinite(voxel[a]) && voxel[a] > 0))
            throw InputError(path + ": grid '" + levelSet->getName() + "' has voxel size " +
                             std::to_string(voxel[a]) + " (positive and finite expected)");
    if (!std::isfinite(levelSet->background()))
        throw InputError(path + ": grid '" + levelSet->getName() +
                         "' has a background that is not finite");
    return levelSet;
}

} // namespace

openvdb::FloatGrid::Ptr readLevelSetFromMemory(const uint8_t* data, size_t size,
                                               const std::string& path, const std::string& gridName)
{
    return pickLevelSet(*io_internal::readVdbGrids(data, size, path), path, gridName);
}

LevelSetFile readLevelSetFile(const std::string& path, const std::string& gridName)
{
    const openvdb::GridPtrVecPtr grids =
        io_internal::readVdbGrids(io_internal::readFile(path), path);
    LevelSetFile f;
    if (gridName.empty()) f.adaptive = AdaptiveGrid::fromGrids(*grids, path);
    f.grid = f.adaptive.empty() ? pickLevelSet(*grids, path, gridName) : f.adaptive.level2;
    return f;
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

std::vector<GridDescription> describeVdb(const std::string& path, std::vector<std::string>* skipped)
{
    const openvdb::GridPtrVecPtr grids =
        io_internal::readVdbGrids(io_internal::readFile(path), path, skipped);
    std::vector<GridDescription> out;
    for (const openvdb::GridBase::Ptr& g : *grids) {
        GridDescription d;
        d.name = g->getName();
        d.gridClass = openvdb::GridBase::gridClassToString(g->getGridClass());
        d.valueType = g->valueType();
        const openvdb::Vec3d vs = g->voxelSize();
        for (int a = 0; a < 3; ++a)
            d.voxelSize[a] = vs[a];
        d.linear = g->transform().isLinear();
        d.activeVoxels = g->activeVoxelCount();
        d.leaves = g->baseTreePtr()->leafCount();
        const openvdb::CoordBBox box = g->evalActiveVoxelBoundingBox();
        d.empty = box.empty();
        if (!d.empty)
            for (int a = 0; a < 3; ++a)
                d.bboxMin[a] = box.min()[a], d.bboxMax[a] = box.max()[a];
        if (auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g)) {
            char text[32];
            std::snprintf(text, sizeof(text), "%g", double(f->background()));
            d.background = text;
        }
        for (auto m = g->beginMeta(); m != g->endMeta(); ++m)
            if (m->second) d.metadata.emplace_back(m->first, m->second->str());
        out.push_back(std::move(d));
    }
    return out;
}

} // namespace io
} // namespace fluidsurf
