// LevelSetIO.cc - level sets in .vdb files: read (validated like every reader), written
// atomically with a content-derived UUID, and described for `fluidsurf info`.
#include <fluidsurf/Error.h>
#include <fluidsurf/io/AtomicFile.h>
#include <fluidsurf/io/LevelSetIO.h>

#include "io/FileBuffer.h"
#include "io/VdbGrids.h"

#include <cerrno>
#include <cmath>
#include <cstdio>
#include <memory>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

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

/// The file's bytes after the UUID, hashed as they are read back a chunk at a time. Read into
/// one vector through a stream iterator, the file took as long as OpenVDB took to write it (0.37
/// s of the 1.7M-particle frame's 0.85 s `write`) and held a second copy of it at the peak.
void makeUuidDeterministic(const std::string& path)
{
    const int fd = ::open(path.c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0) throw OutputError(path + ": cannot read back the written file");
    struct Closer
    {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    // (pread returns short counts only at the end of the file or when interrupted)
    auto readAt = [&](uint8_t* to, size_t n, size_t at) {
        size_t done = 0;
        while (done < n) {
            const ssize_t got = ::pread(fd, to + done, n - done, off_t(at + done));
            if (got < 0 && errno == EINTR) continue;
            if (got < 0) throw OutputError(path + ": cannot read back the written file");
            if (got == 0) break;
            done += size_t(got);
        }
        return done;
    };
    uint8_t head[kUuidOffset + kUuidLength];
    if (readAt(head, sizeof head, 0) < sizeof head || head[kUuidOffset + 8] != '-' ||
        head[kUuidOffset + 13] != '-')
        throw OutputError(path + ": unexpected VDB header layout (OpenVDB version?)");
    constexpr size_t kChunk = size_t(4) << 20;
    const std::unique_ptr<uint8_t[]> chunk(new uint8_t[kChunk]);
    uint64_t h0 = 0xcbf29ce484222325ull, h1 = 0x84222325cbf29ce4ull; // two FNV-1a streams
    for (size_t at = sizeof head;;) {
        const size_t got = readAt(chunk.get(), kChunk, at);
        for (size_t i = 0; i < got; ++i) {
            h0 = (h0 ^ chunk[i]) * 0x100000001b3ull;
            h1 = (h1 ^ chunk[i] ^ 0x5a) * 0x100000001b3ull;
        }
        if (got < kChunk) break;
        at += got;
    }
    char uuid[40];
    std::snprintf(uuid, sizeof(uuid), "%08x-%04x-%04x-%04x-%012llx", unsigned(h0 >> 32),
                  unsigned(h0 >> 16) & 0xffff, (unsigned(h0) & 0x0fff) | 0x4000,
                  (unsigned(h1 >> 48) & 0x3fff) | 0x8000,
                  (unsigned long long)(h1 & 0xffffffffffffull));
    if (::pwrite(fd, uuid, kUuidLength, off_t(kUuidOffset)) != ssize_t(kUuidLength))
        throw OutputError(path + ": cannot write the file header");
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
