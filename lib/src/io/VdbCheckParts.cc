// VdbCheckParts.cc - pieces of a .vdb that both walks check the same way (see VdbCheckParts.h).
#include "io/VdbCheckParts.h"

#include <openvdb/Metadata.h>
#include <openvdb/openvdb.h>

#include <blosc.h>
#include <zlib.h>

#include <set>

namespace fluidsurf {
namespace io_internal {

std::string readVdbString(ByteReader& in, const char* what)
{
    const int32_t len = in.read<int32_t>(false, what);
    if (len < 0) in.fail(std::string("negative length of ") + what);
    const uint8_t* p = in.take(size_t(len), what);
    return std::string(reinterpret_cast<const char*>(p), size_t(len));
}

namespace {

/// The type OpenVDB gives a grid's metadata of this name when it sets it itself (io::Archive,
/// GridBase): one of another type in the file makes that a TypeError. nullptr: any type.
const char* reservedGridMetaType(const std::string& name)
{
    using G = openvdb::GridBase;
    static const std::pair<const char*, const char*> kReserved[] = {
        {G::META_GRID_CLASS, "string"},       {G::META_GRID_CREATOR, "string"},
        {G::META_GRID_NAME, "string"},        {G::META_SAVE_HALF_FLOAT, "bool"},
        {G::META_IS_LOCAL_SPACE, "bool"},     {G::META_VECTOR_TYPE, "string"},
        {G::META_FILE_BBOX_MIN, "vec3i"},     {G::META_FILE_BBOX_MAX, "vec3i"},
        {G::META_FILE_COMPRESSION, "string"}, {G::META_FILE_MEM_BYTES, "int64"},
        {G::META_FILE_VOXEL_COUNT, "int64"}};
    for (const auto& [reserved, type] : kReserved)
        if (name == reserved) return type;
    return nullptr;
}

} // namespace

void copyMetaMap(ByteReader& in, std::vector<uint8_t>& out, const char* what, bool grid)
{
    const int32_t count = in.read<int32_t>(false, what);
    if (count < 0 || size_t(count) > in.remaining() / 12)
        in.fail(std::string("corrupt ") + what + " " + std::to_string(count));
    std::vector<uint8_t> kept;
    int32_t keptCount = 0;
    std::set<std::string> names;
    for (int32_t m = 0; m < count; ++m) {
        const size_t start = in.offset();
        const std::string name = readVdbString(in, "metadata name");
        if (name.empty()) in.fail("empty metadata name");
        // a MetaMap holds each name once; a second of another type makes readMeta throw
        if (!names.insert(name).second)
            in.fail("corrupt metadata: '" + name.substr(0, 40) + "' appears twice");
        const std::string type = readVdbString(in, "metadata type");
        const int32_t len = in.read<int32_t>(false, "metadata value size");
        if (len < 0) in.fail("negative size of metadata '" + name.substr(0, 40) + "'");
        const uint8_t* value = in.take(size_t(len), "metadata value");
        if (type.compare(0, 2, "__") == 0) continue;
        const char* reserved = grid ? reservedGridMetaType(name) : nullptr;
        if (reserved && type != reserved)
            in.fail("corrupt metadata '" + name + "': a " + type.substr(0, 40) + " where OpenVDB " +
                    "keeps a " + reserved);
        if (type != openvdb::StringMetadata::staticTypeName() &&
            openvdb::Metadata::isRegisteredType(type)) {
            const size_t expected = openvdb::Metadata::createMetadata(type)->size();
            if (size_t(len) != expected)
                in.fail("corrupt metadata '" + name.substr(0, 40) + "': a " + type + " of " +
                        std::to_string(len) + " bytes (" + std::to_string(expected) + " expected)");
            if (type == openvdb::BoolMetadata::staticTypeName() && value[0] > 1)
                in.fail("corrupt metadata '" + name.substr(0, 40) + "': bool value " +
                        std::to_string(value[0]));
        }
        kept.insert(kept.end(), in.data() + start, in.data() + in.offset());
        ++keptCount;
    }
    const uint8_t* countBytes = reinterpret_cast<const uint8_t*>(&keptCount);
    out.insert(out.end(), countBytes, countBytes + sizeof(keptCount));
    out.insert(out.end(), kept.begin(), kept.end());
}

void checkBloscChunk(ByteReader& in, const uint8_t* chunk, uint64_t chunkBytes, uint64_t bytes,
                     bool padded, const std::string& what)
{
    constexpr uint64_t kPadBytes = 128; // BLOSC_PAD_BYTES in openvdb/points/StreamCompression.h
    const uint64_t nbytes = chunkBytes >= 16 ? loadAs<uint32_t>(chunk + 4, false) : 0;
    const bool sizeOk = nbytes == bytes || (padded && bytes <= kPadBytes && nbytes == kPadBytes);
    if (chunkBytes < 16 || !sizeOk || loadAs<uint32_t>(chunk + 12, false) != chunkBytes)
        in.fail("corrupt " + what + ": blosc header does not match the chunk (" +
                std::to_string(chunkBytes) + " bytes holding " + std::to_string(bytes) + ")");
}

void decodeBloscChunk(ByteReader& in, const uint8_t* chunk, std::vector<uint8_t>& scratch,
                      const std::string& what)
{
    const size_t nbytes = loadAs<uint32_t>(chunk + 4, false);
    scratch.resize(nbytes);
    const int got = blosc_decompress_ctx(chunk, scratch.data(), nbytes, 1);
    if (got < 0 || size_t(got) != nbytes)
        in.fail("corrupt " + what + ": its blosc data does not decompress (" +
                (got < 0 ? "blosc error " + std::to_string(got)
                         : std::to_string(got) + " of " + std::to_string(nbytes) + " bytes") +
                ")");
}

void decodeZipChunk(ByteReader& in, const uint8_t* chunk, uint64_t chunkBytes, uint64_t bytes,
                    std::vector<uint8_t>& scratch, const std::string& what)
{
    scratch.resize(bytes + 1); // one byte more: a longer stream shows as more than bytes
    uLongf got = uLongf(scratch.size());
    const int status = uncompress(scratch.data(), &got, chunk, uLong(chunkBytes));
    if (status != Z_OK || got != bytes)
        in.fail("corrupt " + what + ": its zip data does not inflate to " + std::to_string(bytes) +
                " bytes");
}

} // namespace io_internal
} // namespace fluidsurf
