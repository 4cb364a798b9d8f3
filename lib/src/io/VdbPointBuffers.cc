// VdbPointBuffers.cc - the leaf buffers of a point grid walked before OpenVDB reads them.
//
// A PointDataGrid's leaves are read in passes (PointDataLeafNode::readBuffers, OpenVDB 10): a
// pass count P, then P passes over every leaf in file order, with A = (P - 4) / 2:
//   0            the size of each leaf's voxel-offset chunk (uint16)
//   1            a header byte and the attribute descriptor (types, names, groups, metadata;
//                with header bit 1, later leaves share the first one and store none), then
//                every array's metadata (byte count, flags, size, stride)
//   2 .. A+1     attribute a's page headers: the arrays of one attribute, leaf after leaf, are
//                cut into pages of up to 1 MiB, each stored raw or blosc-compressed; a leaf's
//                array is a range of a page (compressed arrays, WRITEPAGED)
//   A+2          each leaf's value mask and voxel offsets (2048 bytes, raw or blosc)
//   A+3 .. 2A+2  attribute a's data: each page's bytes where its first array is read, or, for
//                arrays not written in pages, the array itself (a flag byte, raw or blosc)
// OpenVDB trusts all of it: an array longer than its page trips an assertion (an abort), a page
// size of zero another, sizes that disagree read past buffers or free them twice. So each count,
// size and range is checked here against the others and the file, and each blosc chunk decoded
// once, before OpenVDB reads any of it: it must not throw half-way through its passes either.
#include "io/VdbPointBuffers.h"

#include "io/VdbCheckParts.h"

#include <openvdb/points/AttributeArray.h>
#include <openvdb/points/AttributeSet.h>

#include <cstring>
#include <deque>
#include <limits>
#include <map>
#include <set>

namespace fluidsurf {
namespace io_internal {

namespace {

// points/AttributeArray.h serialization flags and array flags
constexpr uint8_t kWriteStrided = 0x1, kWriteUniform = 0x2, kWritePaged = 0x8,
                  kSerializationLimit = 0x10, kConstantStride = 0x8, kFlagsLimit = 0x20;
// OpenVDB keeps page offsets and array sizes in an int, and blosc refuses buffers near 2 GiB:
// a page decompresses into twice its size
constexpr uint64_t kMaxPageBytes = (uint64_t(std::numeric_limits<int32_t>::max()) - 16) / 2;
// no blosc codec OpenVDB writes (LZ4) gets near deflate's 1032:1; a header that promises more
// is a corrupt one asking for memory the file cannot fill
constexpr uint64_t kMaxBloscRatio = 1032;
// far more values than any file holds, and few enough that their bytes fit in 64 bits
constexpr uint64_t kMaxValues = uint64_t(1) << 48;
constexpr size_t kVoxelOffsetBytes = 512 * sizeof(uint32_t);

struct Array
{
    uint64_t bytes = 0;    ///< what the metadata says the array stores (raw or compressed)
    uint64_t expected = 0; ///< what its values take: stride x size x storage, or one value
    bool uniform = false, paged = false;
    bool firstOfPage = false; ///< its page's bytes come with it in the data pass
};

struct Leaf
{
    uint16_t voxelBytes = 0;
    std::vector<Array> arrays;
};

struct Page
{
    int32_t stored = 0;   ///< > 0: blosc bytes; < 0: minus the raw bytes
    uint32_t content = 0; ///< what the arrays in it take
};

class PointBuffersWalk
{
public:
    PointBuffersWalk(ByteReader& in, const std::vector<const uint8_t*>& leafMasks)
        : mIn(in), mMasks(leafMasks), mLeaves(leafMasks.size())
    {
    }

    void run()
    {
        const uint16_t passes = mIn.read<uint16_t>(false, "point grid pass count");
        if (mLeaves.empty()) return; // counting passes over no leaves finds none to write
        if (passes < 4) mIn.fail("corrupt point grid pass count " + std::to_string(passes));
        mAttributes = (size_t(passes) - 4) / 2;
        for (Leaf& leaf : mLeaves)
            leaf.voxelBytes = mIn.read<uint16_t>(false, "voxel offset chunk size");
        descriptorsAndMetadata();
        std::vector<std::vector<Page>> pages(mAttributes);
        for (size_t a = 0; a < mAttributes; ++a)
            pages[a] = pageHeaders(a);
        for (size_t i = 0; i < mLeaves.size(); ++i)
            voxelOffsets(i);
        for (size_t a = 0; a < mAttributes; ++a)
            arrayData(a, pages[a]);
        // the passes after these (cleanup) read nothing
    }

private:
    /// Pass 1: descriptors (one per leaf, or one shared) and each array's metadata.
    void descriptorsAndMetadata()
    {
        const std::vector<uint32_t>* shared = nullptr;
        for (Leaf& leaf : mLeaves) {
            const std::vector<uint32_t>* storage = shared;
            if (!storage) {
                const uint8_t header = *mIn.take(1, "point leaf header");
                if (header > 3)
                    mIn.fail("corrupt point leaf header " + std::to_string(header) +
                             " (flags 1 and 2 are known)");
                mDescriptors.push_back(descriptor());
                storage = &mDescriptors.back();
                if (header & 1) shared = storage;
                if (header & 2) {
                    const uint64_t skip = mIn.read<uint64_t>(false, "point leaf extra bytes");
                    mIn.skip(mIn.checkedCount(skip, 1, "extra bytes of a point leaf"),
                             "point leaf extra bytes");
                }
            }
            if (storage->size() > mAttributes)
                mIn.fail("corrupt point leaf: " + std::to_string(storage->size()) +
                         " attributes where the pass count holds " + std::to_string(mAttributes));
            leaf.arrays.resize(storage->size());
            for (size_t a = 0; a < storage->size(); ++a)
                leaf.arrays[a] = arrayMetadata((*storage)[a]);
        }
    }

    /// AttributeSet::Descriptor::read: types, names with their positions, groups, metadata.
    /// Returns each attribute's storage bytes per value, in position order.
    std::vector<uint32_t> descriptor()
    {
        // an attribute takes at least two type strings, a name and a position: 20 bytes
        const size_t count =
            mIn.checkedCount(mIn.read<uint64_t>(false, "attribute count"), 20, "attributes");
        std::vector<uint32_t> storage(count);
        for (uint32_t& s : storage) {
            openvdb::NamePair type;
            type.first = readVdbString(mIn, "attribute value type");
            type.second = readVdbString(mIn, "attribute codec");
            s = storageBytes(type);
        }
        std::set<std::string> names;
        std::vector<bool> placed(count, false);
        for (size_t n = 0; n < count; ++n) {
            const std::string name = readVdbString(mIn, "attribute name");
            const uint64_t position = mIn.read<uint64_t>(false, "attribute position");
            if (!openvdb::points::AttributeSet::Descriptor::validName(name))
                mIn.fail("corrupt attribute name '" + name.substr(0, 40) + "'");
            if (position >= count || placed[position] || !names.insert(name).second)
                mIn.fail("corrupt attribute table: '" + name.substr(0, 40) +
                         "' repeats a name or a position");
            placed[position] = true;
        }
        const size_t groups =
            mIn.checkedCount(mIn.read<uint64_t>(false, "group count"), 12, "groups");
        for (size_t g = 0; g < groups; ++g) {
            const std::string name = readVdbString(mIn, "group name");
            if (!openvdb::points::AttributeSet::Descriptor::validName(name))
                mIn.fail("corrupt group name '" + name.substr(0, 40) + "'");
            mIn.skip(8, "group offset");
        }
        std::vector<uint8_t> unused;
        copyMetaMap(mIn, unused, "attribute metadata count");
        return storage;
    }

    /// Bytes per stored value of an attribute type, from OpenVDB's registry.
    uint32_t storageBytes(const openvdb::NamePair& type)
    {
        const auto known = mStorage.find(type);
        if (known != mStorage.end()) return known->second;
        if (!openvdb::points::AttributeArray::isRegistered(type))
            mIn.fail("attribute of unknown type (" + type.first.substr(0, 40) + ", " +
                     type.second.substr(0, 40) + ")");
        const uint32_t bytes =
            openvdb::points::AttributeArray::create(type, 1, 1)->storageTypeSize();
        mStorage.emplace(type, bytes);
        return bytes;
    }

    /// TypedAttributeArray::readMetadata, and what the array's bytes must then be.
    Array arrayMetadata(uint32_t storage)
    {
        Array a;
        const uint64_t total = mIn.read<uint64_t>(false, "attribute byte count");
        const uint8_t flags = *mIn.take(1, "attribute flags");
        const uint8_t serialization = *mIn.take(1, "attribute serialization flags");
        const uint64_t size = mIn.read<uint32_t>(false, "attribute size");
        const uint64_t stride =
            serialization & kWriteStrided ? mIn.read<uint32_t>(false, "attribute stride") : 1;
        if (flags >= kFlagsLimit || serialization >= kSerializationLimit || total < 6 ||
            stride == 0)
            mIn.fail("corrupt attribute array header");
        a.bytes = total - 6; // the count includes the flags and the size
        a.uniform = serialization & kWriteUniform;
        a.paged = serialization & kWritePaged;
        // values: size x stride, or a total of 'stride' values where the stride varies
        const uint64_t values = a.uniform ? 1 : flags & kConstantStride ? size * stride : stride;
        if (values > kMaxValues)
            mIn.fail("corrupt attribute array of " + std::to_string(values) + " values");
        a.expected = values * storage;
        if (a.paged && (a.bytes != a.expected || a.bytes == 0 || a.bytes > kMaxPageBytes))
            mIn.fail("corrupt attribute array: " + std::to_string(a.bytes) + " bytes where " +
                     std::to_string(a.expected) + " are needed");
        if (!a.paged && a.uniform && a.bytes != a.expected)
            mIn.fail("corrupt uniform attribute array: " + std::to_string(a.bytes) +
                     " bytes where " + std::to_string(a.expected) + " are needed");
        return a;
    }

    /// Passes 2..A+1 (PagedInputStream::createHandle): attribute a's page headers, one where
    /// a leaf's array starts a page; the arrays must fill each page exactly.
    std::vector<Page> pageHeaders(size_t a)
    {
        std::vector<Page> pages;
        uint64_t used = 0;
        for (Leaf& leaf : mLeaves) {
            if (a >= leaf.arrays.size() || !leaf.arrays[a].paged) continue;
            Array& array = leaf.arrays[a];
            if (pages.empty() || used == pages.back().content) {
                Page p;
                p.stored = mIn.read<int32_t>(false, "attribute page size");
                const int64_t content =
                    p.stored > 0 ? mIn.read<int32_t>(false, "attribute page content size")
                                 : -int64_t(p.stored);
                if (p.stored == 0 || content <= 0 || uint64_t(content) > kMaxPageBytes ||
                    (p.stored > 0 && uint64_t(content) > kMaxBloscRatio * uint64_t(p.stored)))
                    mIn.fail("corrupt attribute page: " + std::to_string(p.stored) +
                             " bytes stored for " + std::to_string(content));
                p.content = uint32_t(content);
                pages.push_back(p);
                used = 0;
                array.firstOfPage = true;
            }
            if (array.bytes > pages.back().content - used)
                mIn.fail("corrupt attribute page: an array of " + std::to_string(array.bytes) +
                         " bytes runs past its page of " + std::to_string(pages.back().content));
            used += array.bytes;
        }
        if (!pages.empty() && used != pages.back().content)
            mIn.fail("corrupt attribute page: its arrays fill " + std::to_string(used) + " of " +
                     std::to_string(pages.back().content) + " bytes");
        return pages;
    }

    /// Pass A+2 (LeafNode::readBuffers with io::readCompressedValues for PointDataIndex32):
    /// the value mask again, then 512 offsets raw (size 0xFFFF) or as one blosc chunk.
    void voxelOffsets(size_t i)
    {
        const uint8_t* mask = mIn.take(64, "point leaf value mask");
        if (std::memcmp(mask, mMasks[i], 64) != 0)
            mIn.fail("corrupt point leaf: its value mask differs from the one in the topology");
        const uint16_t bytes = mIn.read<uint16_t>(false, "voxel offset chunk size");
        if (bytes != mLeaves[i].voxelBytes)
            mIn.fail("corrupt point leaf: its voxel offsets take " + std::to_string(bytes) +
                     " bytes where the size pass says " + std::to_string(mLeaves[i].voxelBytes));
        if (bytes == 0xFFFF) {
            mIn.skip(kVoxelOffsetBytes, "voxel offsets");
            return;
        }
        const uint8_t* chunk = mIn.take(bytes, "voxel offsets");
        checkBloscChunk(mIn, chunk, bytes, kVoxelOffsetBytes, false, "voxel offsets");
        decodeBloscChunk(mIn, chunk, mScratch, "voxel offsets");
    }

    /// Passes A+3..2A+2: attribute a's bytes, leaf after leaf: a page where an array starts
    /// one (PagedInputStream::read), an array of its own otherwise (readBuffers).
    void arrayData(size_t a, const std::vector<Page>& pages)
    {
        size_t next = 0;
        for (const Leaf& leaf : mLeaves) {
            if (a >= leaf.arrays.size()) continue;
            const Array& array = leaf.arrays[a];
            if (array.paged) {
                if (!array.firstOfPage) continue;
                const Page& p = pages[next++];
                if (p.stored < 0) {
                    mIn.skip(p.content, "attribute page");
                    continue;
                }
                const uint8_t* chunk = mIn.take(size_t(p.stored), "attribute page");
                checkBloscChunk(mIn, chunk, uint64_t(p.stored), p.content, true, "attribute page");
                // Page::decompress gives blosc twice the page's size, which must leave it 16
                if (loadAs<uint32_t>(chunk + 4, false) < 16)
                    mIn.fail("corrupt attribute page: blosc data of " + std::to_string(p.content) +
                             " bytes");
                decodeBloscChunk(mIn, chunk, mScratch, "attribute page");
                continue;
            }
            const uint8_t compressed = array.uniform ? 0 : *mIn.take(1, "attribute array flag");
            if (compressed > 1) mIn.fail("corrupt attribute array flag");
            const uint8_t* bytes =
                mIn.take(mIn.checkedCount(array.bytes, 1, "attribute bytes"), "attribute array");
            if (!compressed && array.bytes != array.expected)
                mIn.fail("corrupt attribute array: " + std::to_string(array.bytes) +
                         " bytes where " + std::to_string(array.expected) + " are needed");
            if (compressed) {
                if (array.expected > kMaxBloscRatio * array.bytes || array.expected > kMaxPageBytes)
                    mIn.fail("corrupt attribute array: " + std::to_string(array.bytes) +
                             " compressed bytes for " + std::to_string(array.expected));
                checkBloscChunk(mIn, bytes, array.bytes, array.expected, true, "attribute array");
                decodeBloscChunk(mIn, bytes, mScratch, "attribute array");
            }
        }
    }

    ByteReader& mIn;
    const std::vector<const uint8_t*>& mMasks;
    std::vector<Leaf> mLeaves;
    size_t mAttributes = 0;
    std::deque<std::vector<uint32_t>> mDescriptors; // stable addresses for the shared one
    std::map<openvdb::NamePair, uint32_t> mStorage;
    std::vector<uint8_t> mScratch; // blosc chunks decoded to be sure they decode
};

} // namespace

void walkPointBuffers(ByteReader& in, const std::vector<const uint8_t*>& leafMasks)
{
    PointBuffersWalk(in, leafMasks).run();
}

} // namespace io_internal
} // namespace fluidsurf
