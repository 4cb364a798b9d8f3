// VdbCheck.cc - a .vdb walked node by node before OpenVDB decodes it.
//
// OpenVDB's reader trusts the file. A flipped byte in a node mask, a compression flag or a chunk
// size makes it read past its buffers, allocate gigabytes, loop for minutes or free a half-read
// tree (all seen on corrupted level sets). So every byte it will decode is walked here first,
// with the layout OpenVDB 10 reads (file formats 222-224; RootNode/InternalNode/LeafNode
// readTopology and readBuffers, io::readCompressedValues, bloscFromStream/unzipFromStream):
//   file:  magic, version, library version, offsets flag, UUID, metadata, grid count, grids
//   grid:  descriptor (name, type, instance parent, three offsets), compression flags,
//          metadata, transform, tree (topology of every node, then every leaf's buffer)
// Each value array must be exactly as long as its node and masks say (a blosc header's sizes
// included) and each mask must agree with the others, so OpenVDB's reads stay in bounds.
//
// The walk writes a normalised copy for OpenVDB: each kept grid right after its descriptor with
// offsets that match, minus the delayed-load index (a second, unchecked table of chunk sizes
// that only memory-mapped reading uses) and minus grids the walk cannot check (listed).
// Point grids have the same topology; their leaf buffers, attribute sets in a multi-pass format
// of their own, are walked by VdbPointBuffers.
#include "io/VdbCheck.h"

#include "io/ByteReader.h"
#include "io/VdbCheckParts.h"
#include "io/VdbPointBuffers.h"

#include <fluidsurf/MemoryBudget.h>

#include <algorithm>
#include <array>
#include <cctype>
#include <set>

namespace fluidsurf {
namespace io_internal {

namespace {

// io/Compression.h
constexpr uint32_t kZip = 0x1, kActiveMask = 0x2, kBlosc = 0x4;
enum : int8_t {
    kNoMaskAndOneInactive = 2,
    kMaskAndNoInactive = 3,
    kMaskAndOneInactive = 4,
    kMaskAndTwoInactive = 5,
    kAllValues = 6
};
constexpr uint32_t kMinVersion = 222, kMaxVersion = 224; // node-mask compression .. multipass
constexpr uint32_t kMultiPassVersion = 224;
constexpr const char* kHalfSuffix = "_HalfFloat";
constexpr const char* kPointTree = "Tree_ptdataidx32_5_4_3";

void append(std::vector<uint8_t>& out, const uint8_t* p, size_t n)
{
    out.insert(out.end(), p, p + n);
}

template <typename T> void appendValue(std::vector<uint8_t>& out, T v)
{
    append(out, reinterpret_cast<const uint8_t*>(&v), sizeof(T));
}

void appendString(std::vector<uint8_t>& out, const std::string& s)
{
    appendValue(out, int32_t(s.size()));
    append(out, reinterpret_cast<const uint8_t*>(s.data()), s.size());
}

size_t countOn(const uint8_t* mask, size_t bits)
{
    size_t n = 0;
    for (size_t i = 0; i < bits / 64; ++i)
        n += size_t(__builtin_popcountll(loadAs<uint64_t>(mask + 8 * i, false)));
    return n;
}

/// The transform: a map type name, then that map's fixed-size fields (their read() in
/// openvdb/math/Maps.h). False for another kind of map (frustum), whose size is not known here.
bool skipTransform(ByteReader& in, std::string& map)
{
    map = readVdbString(in, "transform type");
    if (map.size() < 4 || map.size() > 64 || map.compare(map.size() - 3, 3, "Map") != 0)
        in.fail("corrupt transform type '" + map.substr(0, 40) + "'");
    static const std::pair<const char*, size_t> kMapBytes[] = {
        {"UniformScaleMap", 120},   {"ScaleMap", 120},      {"UniformScaleTranslateMap", 144},
        {"ScaleTranslateMap", 144}, {"TranslationMap", 24}, {"AffineMap", 128},
        {"UnitaryMap", 128}};
    for (const auto& [name, bytes] : kMapBytes)
        if (map == name) {
            in.skip(bytes, "transform");
            return true;
        }
    return false;
}

/// How a tree of fixed-size values is stored: root background and tiles at full size, node
/// arrays at full size or, for real types saved as half floats, two bytes per component.
struct ValueLayout
{
    size_t fullBytes = 0, components = 1;
    bool real = false;
};

bool valueLayout(const std::string& treeType, ValueLayout& v)
{
    static const struct
    {
        const char* type;
        ValueLayout layout;
    } kTrees[] = {{"Tree_float_5_4_3", {4, 1, true}},  {"Tree_double_5_4_3", {8, 1, true}},
                  {"Tree_int32_5_4_3", {4, 1, false}}, {"Tree_int64_5_4_3", {8, 1, false}},
                  {"Tree_vec3s_5_4_3", {12, 3, true}}, {"Tree_vec3d_5_4_3", {24, 3, true}},
                  {"Tree_vec3i_5_4_3", {12, 3, false}}};
    for (const auto& t : kTrees)
        if (treeType == t.type) {
            v = t.layout;
            return true;
        }
    return false;
}

/// The tree of a 5-4-3 grid of fixed-size values, walked in the order OpenVDB reads it.
class TreeWalk
{
public:
    /// decode: compressed chunks are decoded as well as checked (see decodeBloscChunk)
    TreeWalk(ByteReader& in, uint32_t compression, const ValueLayout& v, bool half,
             bool decode = false)
        : mIn(in), mCompression(compression), mFullBytes(v.fullBytes),
          mArrayBytes(half && v.real ? 2 * v.components : v.fullBytes), mHalf(half && v.real),
          mDecode(decode)
    {
    }

    /// The topology (root, internal nodes, leaf masks); returns where the leaf buffers start.
    /// ValueError past the memory budget for the tree OpenVDB would build: a few MB of file can
    /// describe gigabytes of internal nodes (tiles far apart each need nodes of 300 KB).
    size_t topology()
    {
        const int32_t buffers = mIn.read<int32_t>(false, "tree buffer count");
        if (buffers != 1) mIn.fail("corrupt tree buffer count " + std::to_string(buffers));
        root();
        requireMemory(mTreeBytes, mIn.source() + ": a grid's tree");
        return mIn.offset();
    }

    /// Each leaf's value mask in the topology, in file order (after topology()).
    const std::vector<const uint8_t*>& leafMasks() const { return mLeafMasks; }

    /// The topology, then every leaf's buffer; returns where the leaf buffers start.
    size_t run()
    {
        const size_t buffersStart = topology();
        for (const uint8_t* topologyMask : mLeafMasks) {
            const uint8_t* mask = mIn.take(64, "leaf value mask");
            if (std::memcmp(mask, topologyMask, 64) != 0)
                mIn.fail("corrupt leaf: its value mask differs from the one in the topology");
            values(512, mask, "leaf values");
        }
        return buffersStart;
    }

private:
    void root()
    {
        mIn.skip(mFullBytes, "root background");
        const uint64_t tiles = mIn.read<uint32_t>(false, "root tile count");
        const uint64_t children = mIn.read<uint32_t>(false, "root child count");
        // a tile is an origin, a value and a flag; a child at least an origin and two masks
        const size_t tileBytes = 12 + mFullBytes + 1, childBytes = 12 + 2 * 4096 + 1;
        if (tiles * tileBytes + children * childBytes > mIn.remaining())
            mIn.fail("corrupt root node: " + std::to_string(tiles) + " tiles and " +
                     std::to_string(children) + " children do not fit in the grid");
        std::set<std::array<int32_t, 3>> keys;
        for (uint64_t t = 0; t < tiles; ++t) {
            keys.insert(origin("root tile"));
            mIn.skip(mFullBytes, "root tile value");
            if (*mIn.take(1, "root tile state") > 1) mIn.fail("corrupt root tile state");
        }
        std::array<int32_t, 3> previous{};
        for (uint64_t c = 0; c < children; ++c) {
            const std::array<int32_t, 3> key = origin("root child");
            // OpenVDB reads the buffers in the order of its table (sorted origins), the
            // topology in file order: the two agree only if the file is sorted
            if ((c > 0 && !(previous < key)) || keys.count(key))
                mIn.fail("corrupt root node: child origins out of order or repeated");
            previous = key;
            internal(5);
        }
    }

    std::array<int32_t, 3> origin(const char* what)
    {
        std::array<int32_t, 3> o;
        for (int32_t& c : o) {
            c = mIn.read<int32_t>(false, what);
            if (c % 4096 != 0) mIn.fail(std::string("corrupt ") + what + " origin");
        }
        return o;
    }

    /// An internal node of 2^(3*log2Dim) entries: child mask, value mask, its tile values,
    /// then its children (internal nodes of log2Dim 4, or leaves).
    void internal(int log2Dim)
    {
        const size_t entries = size_t(1) << (3 * log2Dim), maskBytes = entries / 8;
        // in memory: a table entry each (a child pointer or a value, 8 bytes at least), 3 masks
        mTreeBytes += double(entries) * double(std::max<size_t>(8, (mFullBytes + 7) / 8 * 8)) +
                      3.0 * double(maskBytes);
        const uint8_t* childMask = mIn.take(maskBytes, "internal node child mask");
        const uint8_t* valueMask = mIn.take(maskBytes, "internal node value mask");
        for (size_t i = 0; i < maskBytes; ++i)
            if (childMask[i] & valueMask[i])
                mIn.fail("corrupt internal node: an entry is both a child and an active tile");
        values(entries, valueMask, "internal node values");
        for (size_t word = 0; word < entries / 64; ++word)
            for (uint64_t bits = loadAs<uint64_t>(childMask + 8 * word, false); bits;
                 bits &= bits - 1) {
                if (log2Dim == 5)
                    internal(4);
                else {
                    mLeafMasks.push_back(mIn.take(64, "leaf topology mask"));
                    mTreeBytes += 512.0 * double(mFullBytes) + 128;
                }
            }
    }

    /// io::readCompressedValues: a flag for what follows, inactive values, a selection mask,
    /// then the (active or all) values as one raw, zip or blosc chunk.
    void values(size_t count, const uint8_t* valueMask, const char* what)
    {
        const int8_t flag = int8_t(*mIn.take(1, what));
        if (flag < 0 || flag > kAllValues)
            mIn.fail(std::string("corrupt ") + what + ": compression flag " +
                     std::to_string(int(flag)));
        if (flag == kNoMaskAndOneInactive || flag == kMaskAndOneInactive ||
            flag == kMaskAndTwoInactive)
            mIn.skip(mFullBytes * (flag == kMaskAndTwoInactive ? 2 : 1), "inactive values");
        if (flag >= kMaskAndNoInactive && flag <= kMaskAndTwoInactive)
            mIn.skip(count / 8, "selection mask");
        const size_t stored =
            (mCompression & kActiveMask) && flag != kAllValues ? countOn(valueMask, count) : count;
        if (mHalf && stored == 0) return; // HalfReader reads nothing for an empty array
        const uint64_t bytes = stored * mArrayBytes;
        if (!(mCompression & (kZip | kBlosc))) {
            mIn.skip(bytes, what);
            return;
        }
        const int64_t chunk = mIn.read<int64_t>(false, "compressed chunk size");
        if (chunk <= 0) {
            // stored raw; OpenVDB's blosc path reads it before checking its length
            if (uint64_t(-chunk) != bytes)
                mIn.fail(std::string("corrupt ") + what + ": a raw chunk of " +
                         std::to_string(-chunk) + " bytes where " + std::to_string(bytes) +
                         " are needed");
            mIn.skip(bytes, what);
            return;
        }
        if (uint64_t(chunk) > mIn.remaining())
            mIn.fail(std::string("corrupt ") + what + ": a chunk of " + std::to_string(chunk) +
                     " bytes, " + std::to_string(mIn.remaining()) + " left in the grid");
        const uint8_t* data = mIn.take(size_t(chunk), what);
        if (mCompression & kBlosc) {
            checkBloscChunk(mIn, data, uint64_t(chunk), bytes, false, what);
            if (mDecode) decodeBloscChunk(mIn, data, mScratch, what);
        } else if (mDecode)
            decodeZipChunk(mIn, data, uint64_t(chunk), bytes, mScratch, what);
    }

    ByteReader& mIn;
    const uint32_t mCompression;
    const size_t mFullBytes, mArrayBytes;
    double mTreeBytes = 0; ///< what OpenVDB's tree of the nodes walked so far will take
    const bool mHalf, mDecode;
    std::vector<const uint8_t*> mLeafMasks;
    std::vector<uint8_t> mScratch;
};

struct GridWalk
{
    std::vector<uint8_t> body; ///< the grid's bytes as OpenVDB gets them
    size_t buffersStart = 0;   ///< in the source; 0 where not known
    std::string skipReason;    ///< non-empty: leave the grid out
};

/// One grid's bytes from in's position to its end: where the walk ends, or for a grid that is
/// not walked, the reader's bound when that is the grid's end (hasEnd: the file has grid
/// offsets, or this is its last grid).
GridWalk walkGrid(ByteReader& in, uint32_t version, const std::string& treeType, bool half,
                  bool instance, bool hasEnd)
{
    GridWalk g;
    const uint32_t compression = in.read<uint32_t>(false, "grid compression flags");
    if (compression & ~(kZip | kActiveMask | kBlosc))
        in.fail("corrupt grid compression flags " + std::to_string(compression));
    appendValue(g.body, compression);
    copyMetaMap(in, g.body, "grid metadata count", /*grid=*/true);
    const size_t rest = in.offset();
    std::string map;
    ValueLayout layout;
    if (!skipTransform(in, map))
        g.skipReason = "a " + map + " transform";
    else if (instance)
        ; // shares its parent's tree: nothing follows the transform
    else if (valueLayout(treeType, layout))
        g.buffersStart = TreeWalk(in, compression, layout, half).run();
    else if (treeType == kPointTree) {
        // the same topology as a tree of 4-byte values; then leaf buffers of their own
        if (version < kMultiPassVersion)
            in.fail("a point grid in a file of version " + std::to_string(version) +
                    " (point grids came with version " + std::to_string(kMultiPassVersion) + ")");
        TreeWalk tree(in, compression, ValueLayout{4, 1, false}, false, /*decode=*/true);
        g.buffersStart = tree.topology();
        walkPointBuffers(in, tree.leafMasks());
    } else
        g.skipReason = "a grid type fluidsurf does not read";
    if (!g.skipReason.empty()) {
        if (!hasEnd)
            in.fail("grid of type " + treeType + " (" + g.skipReason +
                    ") in a file without grid offsets, not last: its end cannot be found");
        in.seek(in.size());
        return g;
    }
    append(g.body, in.data() + rest, in.offset() - rest);
    return g;
}

} // namespace

CheckedVdb checkVdb(const uint8_t* data, size_t size, const std::string& src)
{
    static const uint8_t kMagic[8] = {0x20, 0x42, 0x44, 0x56, 0, 0, 0, 0};
    ByteReader in(data, size, src);
    if (size < 8 || std::memcmp(data, kMagic, 8) != 0)
        in.failAt(0, "not an OpenVDB file (missing VDB magic)");
    in.skip(8, "VDB magic");
    const uint32_t version = in.read<uint32_t>(false, "file version");
    if (version < kMinVersion || version > kMaxVersion)
        in.failAt(8, "unsupported VDB file version " + std::to_string(version) + " (" +
                         std::to_string(kMinVersion) + " to " + std::to_string(kMaxVersion) +
                         " are read)");
    in.skip(8, "library version");
    const uint8_t offsetsFlag = *in.take(1, "grid offsets flag");
    if (offsetsFlag > 1) in.fail("corrupt grid offsets flag");
    const bool hasOffsets = offsetsFlag == 1;
    const uint8_t* uuid = in.take(36, "UUID");
    CheckedVdb r;
    std::vector<uint8_t>& out = r.bytes;
    out.reserve(size);
    append(out, data, in.offset());
    // OpenVDB parses the UUID (a tag for caching, not data) and fails on a damaged one with a
    // stream error that reads like a truncated file; the copy gets a blank one instead
    bool uuidOk = true;
    for (size_t i = 0; i < 36; ++i)
        uuidOk &= (i == 8 || i == 13 || i == 18 || i == 23) ? uuid[i] == '-'
                                                            : std::isxdigit(uuid[i]) != 0;
    if (!uuidOk)
        std::memcpy(out.data() + (uuid - data), "00000000-0000-0000-0000-000000000000", 36);
    copyMetaMap(in, out, "file metadata count");
    const int32_t grids = in.read<int32_t>(false, "grid count");
    if (grids < 0 || size_t(grids) > in.remaining() / 36)
        in.fail("corrupt grid count " + std::to_string(grids));
    const size_t countAt = out.size();
    appendValue(out, int32_t(0));
    int32_t kept = 0;
    std::set<std::string> keptNames;
    for (int32_t g = 0; g < grids; ++g) {
        const std::string name = readVdbString(in, "grid name");
        const std::string typeName = readVdbString(in, "grid type");
        const std::string parent = readVdbString(in, "grid instance parent");
        const size_t descriptorEnd = in.offset() + 24;
        const int64_t gridPos = in.read<int64_t>(false, "grid offset");
        const int64_t blockPos = in.read<int64_t>(false, "grid block offset");
        const int64_t endPos = in.read<int64_t>(false, "grid end offset");
        const std::string label = "grid '" + name.substr(0, 60) + "'";
        if (hasOffsets) {
            // an instance has no buffers of its own: block offset 0
            const bool blockOk =
                parent.empty() ? gridPos <= blockPos && blockPos <= endPos : blockPos == 0;
            if (!(size_t(gridPos) == descriptorEnd && blockOk && gridPos <= endPos))
                in.fail("corrupt offsets in the descriptor of " + label);
            if (uint64_t(endPos) > size)
                in.fail(label + " ends at byte " + std::to_string(endPos) + " but the file has " +
                        std::to_string(size) + " bytes (truncated file?)");
        }
        const bool half = typeName.size() > std::strlen(kHalfSuffix) &&
                          typeName.compare(typeName.size() - std::strlen(kHalfSuffix),
                                           std::string::npos, kHalfSuffix) == 0;
        const std::string treeType =
            half ? typeName.substr(0, typeName.size() - std::strlen(kHalfSuffix)) : typeName;
        ByteReader grid(data, hasOffsets ? size_t(endPos) : size, src);
        grid.seek(descriptorEnd);
        GridWalk walk;
        try {
            walk = walkGrid(grid, version, treeType, half, !parent.empty(),
                            hasOffsets || g + 1 == grids);
        } catch (const InputError& e) {
            throw InputError(std::string(e.what()) + " in " + label);
        }
        if (hasOffsets && grid.offset() != size_t(endPos))
            grid.fail("corrupt " + label + ": its data ends before the end its descriptor gives (" +
                      std::to_string(endPos) + ")");
        if (walk.buffersStart && hasOffsets && walk.buffersStart != size_t(blockPos))
            in.fail("corrupt offsets in the descriptor of " + label +
                    " (its buffers start elsewhere)");
        in.seek(grid.offset());
        if (walk.skipReason.empty() && !parent.empty() && !keptNames.count(parent))
            walk.skipReason = "an instance of grid '" + parent.substr(0, 60) + "', not read";
        if (!walk.skipReason.empty()) {
            r.skipped.push_back(name + " (" + treeType + "): " + walk.skipReason);
            continue;
        }
        appendString(out, name);
        appendString(out, typeName);
        appendString(out, parent);
        if (hasOffsets) {
            // the metadata may have shrunk; everything after it moves with it
            const int64_t newGridPos = int64_t(out.size() + 24);
            const int64_t growth = int64_t(walk.body.size()) - (endPos - gridPos);
            appendValue(out, newGridPos);
            appendValue(out, blockPos ? blockPos - gridPos + newGridPos + growth : 0);
            appendValue(out, newGridPos + int64_t(walk.body.size()));
        } else {
            appendValue(out, gridPos);
            appendValue(out, blockPos);
            appendValue(out, endPos);
        }
        append(out, walk.body.data(), walk.body.size());
        keptNames.insert(name);
        ++kept;
    }
    std::memcpy(out.data() + countAt, &kept, sizeof(kept));
    return r;
}

} // namespace io_internal
} // namespace fluidsurf
