// BgeoIO.cc - Houdini classic binary geometry, version 5 ("BgeoV" magic), as written by partio
// and SPlisHSPlasH, optionally gzip-compressed. Big-endian throughout.
//
// Layout read: magic, 'V', version, then eight int32 counts (points, prims, point groups, prim
// groups, point/vertex/prim/detail attributes); the point attribute definitions (name, size,
// Houdini type, defaults); then per point x y z w followed by its attribute values. Primitives and
// anything after the points are not needed for particles and are not read.
#include "io/BigEndian.h"
#include "io/ByteReader.h"
#include "io/FileBuffer.h"
#include "io/Formats.h"
#include "io/GzipStream.h"
#include "io/StreamFile.h"

#include "util/Memory.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/MemoryBudget.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_group.h>

#include <cstring>
#include <limits>
#include <optional>

namespace fluidsurf {
namespace io_internal {

namespace {

enum HoudiniType : int32_t { kFloat = 0, kInt = 1, kString = 2, kIndex = 4, kVector = 5 };

struct AttrDef
{
    std::string name;
    int size = 0;
    int32_t type = kFloat;
};

} // namespace

namespace {
struct Header
{
    int32_t points = 0;
    std::vector<AttrDef> defs;
    size_t valuesPerPoint = 4; ///< x y z w, then the attributes' components
};

/// Magic, version, counts and the point attribute definitions; in is left at the point data.
Header readHeader(ByteReader& in, const uint8_t* data, size_t size)
{
    Header h;
    if (size < 5 || std::memcmp(data, "BgeoV", 5) != 0) {
        if (size >= 4 && std::memcmp(data, "Bgeo", 4) == 0)
            in.failAt(4, "unsupported BGEO flavour (only classic binary 'BgeoV' version 5)");
        if (size >= 1 && data[0] == '{')
            in.failAt(0, "this is a Houdini JSON geometry (new .bgeo/.geo); only classic BGEO v5 "
                         "is supported");
        in.failAt(0, "not a BGEO file (missing 'BgeoV' magic)");
    }
    in.skip(5, "magic");
    const int32_t version = in.read<int32_t>(true, "version");
    if (version != 5)
        in.failAt(5, "unsupported BGEO version " + std::to_string(version) + " (5 expected)");
    int32_t counts[8];
    for (int32_t& c : counts) {
        c = in.read<int32_t>(true, "header counts");
        if (c < 0) in.failAt(in.offset() - 4, "negative count " + std::to_string(c) + " in header");
    }
    const int32_t nPointAttrib = counts[4];
    h.points = counts[0];

    std::vector<AttrDef>& defs = h.defs;
    defs.resize(size_t(in.checkedCount(uint64_t(nPointAttrib), 8, "attribute definitions")));
    size_t& valuesPerPoint = h.valuesPerPoint;
    for (AttrDef& d : defs) {
        const uint16_t len = in.read<uint16_t>(true, "attribute name length");
        const uint8_t* name = in.take(len, "attribute name");
        d.name.assign(reinterpret_cast<const char*>(name), len);
        d.size = in.read<int16_t>(true, "attribute size");
        d.type = in.read<int32_t>(true, "attribute type");
        if (d.size < 1 || d.size > 16)
            in.fail("attribute '" + d.name + "' has invalid size " + std::to_string(d.size));
        if (d.type == kIndex || d.type == kString) {
            // A string table follows; each point stores an index into it, kept as an int.
            const int32_t strings = in.read<int32_t>(true, "string count");
            if (strings < 0) in.fail("negative string count");
            in.checkedCount(uint64_t(strings), 2, "strings");
            for (int32_t s = 0; s < strings; ++s)
                in.skip(in.read<uint16_t>(true, "string length"), "string");
        } else if (d.type == kFloat || d.type == kInt || d.type == kVector) {
            if (d.type == kVector && d.size != 3)
                in.fail("vector attribute '" + d.name + "' has size " + std::to_string(d.size));
            in.skip(size_t(d.size) * 4, "attribute defaults");
        } else {
            in.fail("attribute '" + d.name + "' has unsupported Houdini type " +
                    std::to_string(d.type));
        }
        valuesPerPoint += size_t(d.size);
    }

    return h;
}
} // namespace

namespace {
/// The points' arrays, sized for n, and their decoding from records of the file's layout.
struct Points
{
    const Header& header;
    ParticleSet set;
    std::vector<std::vector<float>> floats;
    std::vector<std::vector<int64_t>> ints;

    /// Arrays for n points; reserveOnly: their storage only reserved (address space, no pages),
    /// each point's made as ensure() reaches it, so that a header that promises more points
    /// than the stream holds costs what the stream holds (a gzip stream cannot be sized first).
    Points(const Header& h, size_t n, const std::string& src, bool reserveOnly = false)
        : header(h), floats(h.defs.size()), ints(h.defs.size())
    {
        requireMemory(double(n) * double(bytesPerPoint(h)),
                      src + ": reading the " + std::to_string(n) + " points its header promises");
        if (reserveOnly) {
            set.positions.reserve(n);
            for (size_t a = 0; a < h.defs.size(); ++a)
                (isFloat(a) ? floats[a].reserve(n * h.defs[a].size)
                            : ints[a].reserve(n * h.defs[a].size));
            return;
        }
        ensure(n);
    }
    /// The arrays sized for count points (within what they reserved: no copy).
    void ensure(size_t count)
    {
        util::resizeInParallel(set.positions, count);
        for (size_t a = 0; a < header.defs.size(); ++a) {
            if (isFloat(a))
                floats[a].resize(count * header.defs[a].size);
            else
                ints[a].resize(count * header.defs[a].size);
        }
    }
    static size_t bytesPerPoint(const Header& h)
    {
        size_t bytes = sizeof(Vec3f);
        for (const auto& d : h.defs)
            bytes += size_t(d.size) * (d.type == kFloat || d.type == kVector ? 4 : 8);
        return bytes;
    }
    bool isFloat(size_t a) const
    {
        return header.defs[a].type == kFloat || header.defs[a].type == kVector;
    }
    size_t recordBytes() const { return header.valuesPerPoint * 4; }

    /// Points [first, first + count) from their records at p, on all threads.
    void decode(const uint8_t* p, size_t first, size_t count)
    {
        const size_t bytes = recordBytes();
        tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 4096),
                          [&](const tbb::blocked_range<size_t>& r) {
                              for (size_t k = r.begin(); k != r.end(); ++k)
                                  decodeOne(p + k * bytes, first + k);
                          });
    }
    void decodeOne(const uint8_t* p, size_t i)
    {
        set.positions[i] =
            Vec3f(loadAs<float>(p, true), loadAs<float>(p + 4, true), loadAs<float>(p + 8, true));
        p += 16; // w is the homogeneous coordinate, 1 for particles
        for (size_t a = 0; a < header.defs.size(); ++a) {
            const int s = header.defs[a].size;
            if (isFloat(a)) {
                for (int c = 0; c < s; ++c)
                    floats[a][i * s + c] = loadAs<float>(p + 4 * c, true);
            } else {
                for (int c = 0; c < s; ++c)
                    ints[a][i * s + c] = loadAs<int32_t>(p + 4 * c, true);
            }
            p += 4 * s;
        }
    }
    ParticleSet finish()
    {
        for (size_t a = 0; a < header.defs.size(); ++a) {
            if (isFloat(a))
                set.addFloat(header.defs[a].name, header.defs[a].size, std::move(floats[a]));
            else
                set.addInt(header.defs[a].name, header.defs[a].size, std::move(ints[a]));
        }
        return std::move(set);
    }
};

/// A gzip-compressed file, inflated a slice at a time into its points: no buffer of the whole
/// file (the 13.1M drop's 210 MB), and each slice decoded on the other threads while the next
/// one inflates.
ParticleSet readGzipBgeo(const uint8_t* data, size_t size, const std::string& src)
{
    const std::string inflatedSource = src + " (after gzip)";
    GzipInflater in(data, size, src);
    // The header from a growing prefix: a valid header followed by gigabytes of compressed
    // zeros costs its points, not its tail.
    std::vector<uint8_t> head;
    Header h;
    size_t offset = 0;
    for (size_t want = size_t(1) << 16;; want *= 16) {
        const size_t had = head.size();
        head.resize(want);
        head.resize(had + in.read(head.data() + had, want - had));
        ByteReader probe(head.data(), head.size(), inflatedSource);
        try {
            h = readHeader(probe, head.data(), head.size());
            offset = probe.offset();
            break;
        } catch (const InputError&) {
            // The whole stream is here, or 64 MiB hold no header: the error is real.
            if (in.ended() || want >= (size_t(1) << 26)) throw;
        }
    }
    const size_t n = size_t(h.points), recordBytes = h.valuesPerPoint * 4;
    const uint64_t pointBytes = uint64_t(n) * recordBytes;
    const size_t needed = offset + size_t(std::min<uint64_t>(pointBytes, uint64_t(1) << 40));
    // deflate makes at most 1032 bytes of one: more points than that are not there, and
    // nothing is allocated for them
    const bool mayHold = pointBytes <= 1032 * uint64_t(size) + (uint64_t(1) << 16);
    if (mayHold) {
        Points points(h, n, src, /*reserveOnly=*/true);
        const size_t perSlice = std::max<size_t>(1, (size_t(4) << 20) / recordBytes);
        std::vector<uint8_t> slices[2] = {std::vector<uint8_t>(perSlice * recordBytes),
                                          std::vector<uint8_t>(perSlice * recordBytes)};
        // the records already in the head first
        size_t headAt = offset,
               carried = size_t(std::min<uint64_t>(head.size() - offset, pointBytes));
        tbb::task_group decoding;
        size_t done = 0;
        int at = 0;
        try {
            while (done < n) {
                const size_t count = std::min(perSlice, n - done), bytes = count * recordBytes;
                uint8_t* slice = slices[at].data();
                const size_t fromHead = std::min(carried, bytes);
                std::memcpy(slice, head.data() + headAt, fromHead);
                headAt += fromHead, carried -= fromHead;
                if (in.read(slice + fromHead, bytes - fromHead) < bytes - fromHead) break;
                decoding.wait(); // the other slice is free again, and nothing writes the arrays
                points.ensure(done + count);
                decoding.run([&points, slice, done, count] { points.decode(slice, done, count); });
                done += count;
                at ^= 1;
            }
        } catch (...) {
            decoding.wait();
            throw;
        }
        decoding.wait();
        if (done == n) {
            // the rest only as far as the CRC: primitives and groups after the points are
            // smaller than the points for particles, so more is a bomb
            in.skipToEnd(needed + (uint64_t(1) << 26), in.produced() - needed);
            return points.finish();
        }
    }
    // The stream ends inside the points: the message names what is there.
    bool complete = false;
    const std::vector<uint8_t> all = gunzipPrefix(data, size, src, needed, complete);
    ByteReader whole(all.data(), all.size(), inflatedSource);
    readHeader(whole, all.data(), all.size());
    whole.checkedCount(uint64_t(h.points), recordBytes, "points");
    throw InputError(inflatedSource + ": the points end early (truncated or corrupt file)");
}
} // namespace

std::optional<ParticleSet> readBgeo(const OpenFile& file, const std::string& src,
                                    std::string* detail)
{
    const std::vector<uint8_t> head = file.readHead(size_t(1) << 16);
    if (isGzip(head.data(), head.size())) return std::nullopt;
    ByteReader probe(head.data(), head.size(), src);
    Header h;
    try {
        h = readHeader(probe, head.data(), head.size());
    } catch (const InputError&) {
        return std::nullopt; // a larger header, or the message from the whole file
    }
    const uint64_t offset = probe.offset(), recordBytes = h.valuesPerPoint * 4;
    const size_t n = size_t(h.points);
    if (offset + uint64_t(n) * recordBytes > file.size()) return std::nullopt;
    Points points(h, n, src);
    forRecordSlices(file, offset, n, recordBytes,
                    [&](size_t first, size_t count, const uint8_t* records) {
                        for (size_t k = 0; k < count; ++k)
                            points.decodeOne(records + k * recordBytes, first + k);
                    });
    if (detail) *detail = "v5, uncompressed";
    return points.finish();
}

ParticleSet readBgeo(const uint8_t* data, size_t size, const std::string& src, std::string* detail)
{
    const bool zipped = isGzip(data, size);
    if (detail) *detail = std::string("v5") + (zipped ? ", gzip" : ", uncompressed");
    if (zipped) return readGzipBgeo(data, size, src);
    ByteReader in(data, size, src);
    const Header h = readHeader(in, data, size);
    const size_t n = in.checkedCount(uint64_t(h.points), h.valuesPerPoint * 4, "points");
    Points points(h, n, src);
    points.decode(in.take(n * h.valuesPerPoint * 4, "point data"), 0, n);
    return points.finish();
}

namespace {
void put32(std::string& out, uint32_t v)
{
    appendBigEndian(out, &v, 1);
}
void put16(std::string& out, uint16_t v)
{
    out += char(v >> 8);
    out += char(v);
}

/// The file into out (a StreamFile, or a GzipStream for `.bgeo.gz`).
template <typename Out> void putBgeo(const ParticleSet& ps, Out& out)
{
    ps.validate();
    if (ps.size() > size_t(std::numeric_limits<int32_t>::max()))
        throw OutputError("BGEO v5 holds at most 2^31-1 points");
    for (const Attribute& a : ps.attributes) {
        if (a.name.size() > 65535)
            throw OutputError("attribute name too long for BGEO: " + a.name.substr(0, 40));
        for (int64_t v : a.ints)
            if (v < std::numeric_limits<int32_t>::min() || v > std::numeric_limits<int32_t>::max())
                throw OutputError("attribute '" + a.name + "' holds the value " +
                                  std::to_string(v) + ", beyond BGEO's 32-bit integers");
    }
    std::string head = "BgeoV";
    put32(head, 5);
    const uint32_t counts[8] = {
        uint32_t(ps.size()), 0, 0, 0, uint32_t(ps.attributes.size()), 0, 0, 0};
    for (uint32_t c : counts)
        put32(head, c);
    size_t perPoint = 16;
    for (const Attribute& a : ps.attributes) {
        put16(head, uint16_t(a.name.size()));
        head += a.name;
        put16(head, uint16_t(a.components));
        const bool isFloat = a.type == AttributeType::Float;
        put32(head, isFloat ? (a.components == 3 ? kVector : kFloat) : kInt);
        for (int c = 0; c < a.components; ++c)
            put32(head, 0); // defaults
        perPoint += 4 * size_t(a.components);
    }
    out.write(head);
    io::writeItems(out, ps.size(), perPoint, [&](std::string& o, size_t i) {
        const Vec3f& p = ps.positions[i];
        put32(o, bitsOf(p.x));
        put32(o, bitsOf(p.y));
        put32(o, bitsOf(p.z));
        put32(o, bitsOf(1.f));
        for (const Attribute& a : ps.attributes)
            for (int c = 0; c < a.components; ++c) {
                const size_t k = i * a.components + c;
                put32(o, a.type == AttributeType::Float ? bitsOf(a.floats[k])
                                                        : uint32_t(int32_t(a.ints[k])));
            }
    });
    out.write(std::string("\x00\xff", 2)); // begin/end of the (empty) extra section, as partio
                                           // writes it
}

} // namespace

void writeBgeo(const ParticleSet& ps, io::StreamFile& out)
{
    putBgeo(ps, out);
}

void writeBgeo(const ParticleSet& ps, io::GzipStream& out)
{
    putBgeo(ps, out);
}

} // namespace io_internal
} // namespace fluidsurf
