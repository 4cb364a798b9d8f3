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

#include <limits>

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

ParticleSet readBgeo(const uint8_t* data, size_t size, const std::string& src, std::string* detail)
{
    std::vector<uint8_t> inflated;
    const bool zipped = isGzip(data, size);
    if (zipped) {
        // Inflate only what the header promises (header, definitions, points): a valid header
        // followed by gigabytes of compressed zeros costs its points, not its tail. The header
        // is read from a growing prefix first.
        bool complete = false;
        size_t want = size_t(1) << 16;
        size_t needed = 0;
        for (;;) {
            inflated = gunzipPrefix(data, size, src, want, complete);
            ByteReader probe(inflated.data(), inflated.size(), src + " (after gzip)");
            try {
                const Header h = readHeader(probe, inflated.data(), inflated.size());
                const uint64_t bytes = uint64_t(h.points) * h.valuesPerPoint * 4;
                needed = probe.offset() + size_t(std::min<uint64_t>(bytes, uint64_t(1) << 40));
                break;
            } catch (const InputError&) {
                // The whole stream is here, or 64 MiB hold no header: the error is real.
                if (complete || want >= (size_t(1) << 26)) throw;
                want *= 16;
            }
        }
        // Then exactly the points, and the rest only as far as the CRC: primitives and groups
        // after the points are smaller than the points for particles, so more is a bomb.
        if (!complete)
            inflated = gunzipPrefix(data, size, src, needed, complete, needed + (size_t(1) << 26));
        data = inflated.data();
        size = inflated.size();
    }
    ByteReader in(data, size, src + (zipped ? " (after gzip)" : ""));
    const Header h = readHeader(in, data, size);
    const std::vector<AttrDef>& defs = h.defs;
    const size_t valuesPerPoint = h.valuesPerPoint;
    const int32_t nPoints = h.points;
    const size_t n = in.checkedCount(uint64_t(nPoints), valuesPerPoint * 4, "points");
    const uint8_t* p = in.take(n * valuesPerPoint * 4, "point data");
    ParticleSet set;
    util::resizeInParallel(set.positions, n);
    std::vector<std::vector<float>> floats(defs.size());
    std::vector<std::vector<int64_t>> ints(defs.size());
    for (size_t a = 0; a < defs.size(); ++a) {
        if (defs[a].type == kFloat || defs[a].type == kVector)
            floats[a].resize(n * defs[a].size);
        else
            ints[a].resize(n * defs[a].size);
    }
    for (size_t i = 0; i < n; ++i) {
        set.positions[i] =
            Vec3f(loadAs<float>(p, true), loadAs<float>(p + 4, true), loadAs<float>(p + 8, true));
        p += 16; // w is the homogeneous coordinate, 1 for particles
        for (size_t a = 0; a < defs.size(); ++a) {
            const int s = defs[a].size;
            if (defs[a].type == kFloat || defs[a].type == kVector) {
                for (int c = 0; c < s; ++c)
                    floats[a][i * s + c] = loadAs<float>(p + 4 * c, true);
            } else {
                for (int c = 0; c < s; ++c)
                    ints[a][i * s + c] = loadAs<int32_t>(p + 4 * c, true);
            }
            p += 4 * s;
        }
    }
    for (size_t a = 0; a < defs.size(); ++a) {
        if (defs[a].type == kFloat || defs[a].type == kVector)
            set.addFloat(defs[a].name, defs[a].size, std::move(floats[a]));
        else
            set.addInt(defs[a].name, defs[a].size, std::move(ints[a]));
    }
    if (detail) *detail = std::string("v5") + (zipped ? ", gzip" : ", uncompressed");
    return set;
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
