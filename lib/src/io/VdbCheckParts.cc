// VdbCheckParts.cc - pieces of a .vdb that both walks check the same way (see VdbCheckParts.h).
#include "io/VdbCheckParts.h"

#include <openvdb/Metadata.h>
#include <openvdb/openvdb.h>

namespace fluidsurf {
namespace io_internal {

std::string readVdbString(ByteReader& in, const char* what)
{
    const int32_t len = in.read<int32_t>(false, what);
    if (len < 0) in.fail(std::string("negative length of ") + what);
    const uint8_t* p = in.take(size_t(len), what);
    return std::string(reinterpret_cast<const char*>(p), size_t(len));
}

void copyMetaMap(ByteReader& in, std::vector<uint8_t>& out, const char* what)
{
    const int32_t count = in.read<int32_t>(false, what);
    if (count < 0 || size_t(count) > in.remaining() / 12)
        in.fail(std::string("corrupt ") + what + " " + std::to_string(count));
    std::vector<uint8_t> kept;
    int32_t keptCount = 0;
    for (int32_t m = 0; m < count; ++m) {
        const size_t start = in.offset();
        const std::string name = readVdbString(in, "metadata name");
        if (name.empty()) in.fail("empty metadata name");
        const std::string type = readVdbString(in, "metadata type");
        const int32_t len = in.read<int32_t>(false, "metadata value size");
        if (len < 0) in.fail("negative size of metadata '" + name.substr(0, 40) + "'");
        const uint8_t* value = in.take(size_t(len), "metadata value");
        if (type.compare(0, 2, "__") == 0) continue;
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

} // namespace io_internal
} // namespace fluidsurf
