// VtkXmlReader.cc - VTK XML UnstructuredGrid (.vtu) and PolyData (.vtp) point sets.
// DataArray formats: ascii, binary (inline base64) and appended (raw or base64 encoding);
// optional vtkZLibDataCompressor blocks; UInt32 or UInt64 headers; either byte order.
// Several <Piece>s are concatenated.
#include "io/FileBuffer.h"
#include "io/TextParse.h"
#include "io/XmlScan.h"

#include "util/Memory.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/MemoryBudget.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <set>

namespace fluidsurf {
namespace io_internal {

namespace {

struct ArrayInfo
{
    XmlTag tag;
    enum { Points, PointData, Other } role = Other;
    size_t textBegin = 0, textEnd = 0; // inline content
    size_t piece = 0;
};

/// An array's binary payload: where it lies in the file's bytes (raw), or decoded (base64).
struct Payload
{
    std::string decoded;
    const uint8_t* raw = nullptr; // raw: no copy of the array
    size_t rawSize = 0;
    const uint8_t* data() const
    {
        return raw ? raw : reinterpret_cast<const uint8_t*>(decoded.data());
    }
    size_t size() const { return raw ? rawSize : decoded.size(); }
};

struct ScalarType
{
    size_t size = 0;
    bool isFloat = false, isSigned = false;
};

bool scalarType(const std::string& name, ScalarType& t)
{
    static const struct
    {
        const char* name;
        ScalarType t;
    } kTypes[] = {
        {"Int8", {1, false, true}},    {"UInt8", {1, false, false}},  {"Int16", {2, false, true}},
        {"UInt16", {2, false, false}}, {"Int32", {4, false, true}},   {"UInt32", {4, false, false}},
        {"Int64", {8, false, true}},   {"UInt64", {8, false, false}}, {"Float32", {4, true, true}},
        {"Float64", {8, true, true}},
    };
    for (const auto& k : kTypes)
        if (name == k.name) {
            t = k.t;
            return true;
        }
    return false;
}

class VtkXmlParser
{
public:
    VtkXmlParser(const uint8_t* data, size_t size, const std::string& src)
        : in(data, size, src), mSrc(src)
    {
    }

    ParticleSet parse(std::string* detail)
    {
        scanStructure();
        std::string how;
        ParticleSet result;
        for (size_t p = 0; p < mPieceCounts.size(); ++p) {
            ParticleSet piece;
            const size_t n = mPieceCounts[p];
            bool havePoints = false;
            for (const ArrayInfo& a : mArrays) {
                if (a.piece != p || a.role == ArrayInfo::Other) continue;
                const std::string fmt = attr(a.tag, "format", "ascii");
                if (how.find(fmt) == std::string::npos) how += (how.empty() ? "" : ", ") + fmt;
                const int comps = components(a);
                std::vector<float> fv; // float(value), as through a double before
                std::vector<int64_t> iv;
                const ScalarType t = typeOf(a);
                decodeArray(a, uint64_t(n) * uint64_t(comps), t, fv, iv);
                if (a.role == ArrayInfo::Points) {
                    if (comps != 3) in.failAt(a.tag.begin, "Points array must have 3 components");
                    util::resizeInParallel(piece.positions, n);
                    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 15),
                                      [&](const tbb::blocked_range<size_t>& r) {
                                          for (size_t i = r.begin(); i != r.end(); ++i)
                                              piece.positions[i] =
                                                  Vec3f(fv[3 * i], fv[3 * i + 1], fv[3 * i + 2]);
                                      });
                    havePoints = true;
                } else if (t.isFloat) {
                    piece.addFloat(attr(a.tag, "Name"), comps, std::move(fv));
                } else {
                    piece.addInt(attr(a.tag, "Name"), comps, std::move(iv));
                }
            }
            if (!havePoints && n > 0)
                in.fail("piece " + std::to_string(p) + " has no <Points> array");
            piece.positions.resize(n);
            append(result, std::move(piece), p);
        }
        if (detail) {
            *detail = mType + ", " + how;
            if (!mCompressor.empty()) *detail += ", " + mCompressor;
            if (!mAppendedEncoding.empty()) *detail += " (" + mAppendedEncoding + ")";
        }
        return result;
    }

private:
    ByteReader in;
    std::string mSrc, mType, mCompressor, mAppendedEncoding;
    bool mBigEndian = false;
    size_t mHeaderSize = 4;
    std::vector<size_t> mPieceCounts;
    std::vector<ArrayInfo> mArrays;
    size_t mAppendedStart = 0; // first byte after '_'
    bool mHaveAppended = false;

    void scanStructure()
    {
        XmlTag t;
        bool haveRoot = false, inPoints = false, inPointData = false;
        while (nextXmlTag(in, t)) {
            if (!haveRoot) {
                if (t.name != "VTKFile")
                    in.failAt(t.begin, "not a VTK XML file (no <VTKFile> root)");
                haveRoot = true;
                mType = attr(t, "type");
                if (mType != "UnstructuredGrid" && mType != "PolyData")
                    in.failAt(t.begin,
                              "VTKFile type '" + mType.substr(0, 40) +
                                  "' is not a point set (UnstructuredGrid or PolyData expected)");
                const std::string order = attr(t, "byte_order", "LittleEndian");
                if (order != "LittleEndian" && order != "BigEndian")
                    in.failAt(t.begin, "bad byte_order");
                mBigEndian = order == "BigEndian";
                const std::string header = attr(t, "header_type", "UInt32");
                if (header == "UInt64")
                    mHeaderSize = 8;
                else if (header == "UInt32")
                    mHeaderSize = 4;
                else
                    in.failAt(t.begin, "unsupported header_type '" + header.substr(0, 40) + "'");
                mCompressor = attr(t, "compressor");
                if (!mCompressor.empty() && mCompressor != "vtkZLibDataCompressor")
                    in.failAt(t.begin, "compressor '" + mCompressor.substr(0, 60) +
                                           "' is not supported (only vtkZLibDataCompressor)");
                continue;
            }
            if (t.name == "Piece" && !t.isEnd) {
                int64_t n;
                const std::string s = attr(t, "NumberOfPoints");
                if (!parseInt(s.data(), s.data() + s.size(), n) || n < 0)
                    in.failAt(t.begin, "Piece has no valid NumberOfPoints");
                mPieceCounts.push_back(size_t(std::min<int64_t>(n, int64_t(1) << 48)));
            } else if (t.name == "Points") {
                inPoints = !t.isEnd && !t.selfClosing;
            } else if (t.name == "PointData") {
                inPointData = !t.isEnd && !t.selfClosing;
            } else if (t.name == "DataArray" && !t.isEnd) {
                if (mPieceCounts.empty()) in.failAt(t.begin, "DataArray outside a <Piece>");
                ArrayInfo a;
                a.tag = t;
                a.piece = mPieceCounts.size() - 1;
                a.role = inPoints ? ArrayInfo::Points
                                  : (inPointData ? ArrayInfo::PointData : ArrayInfo::Other);
                if (!t.selfClosing) {
                    a.textBegin = in.offset();
                    XmlTag close;
                    // content up to the matching </DataArray> (InformationKey children allowed)
                    while (nextXmlTag(in, close) && !(close.isEnd && close.name == "DataArray")) {
                    }
                    a.textEnd = close.begin;
                }
                mArrays.push_back(std::move(a));
            } else if (t.name == "AppendedData" && !t.isEnd) {
                mAppendedEncoding = attr(t, "encoding", "raw");
                if (mAppendedEncoding != "raw" && mAppendedEncoding != "base64")
                    in.failAt(t.begin, "unsupported AppendedData encoding '" +
                                           mAppendedEncoding.substr(0, 40) + "'");
                size_t p = in.offset();
                while (p < in.size() && isSpace(in.data()[p]))
                    ++p;
                if (p >= in.size() || in.data()[p] != '_')
                    in.failAt(p, "AppendedData does not start with '_'");
                mAppendedStart = p + 1;
                mHaveAppended = true;
                break; // raw bytes follow: no more tags to scan
            }
        }
        if (!haveRoot) in.failAt(0, "not a VTK XML file (no <VTKFile> root)");
        if (mPieceCounts.empty()) in.fail("no <Piece> element");
        // VTK always closes the root; its absence means the file was cut short.
        const size_t tail = std::min<size_t>(in.size(), 256);
        const std::string end(reinterpret_cast<const char*>(in.data() + in.size() - tail), tail);
        if (end.find("</VTKFile>") == std::string::npos)
            in.failAt(in.size(), "file ends without </VTKFile> (truncated file?)");
    }

    int components(const ArrayInfo& a)
    {
        int64_t c = 1;
        const std::string s = attr(a.tag, "NumberOfComponents", "1");
        if (!parseInt(s.data(), s.data() + s.size(), c) || c < 1 || c > 16)
            in.failAt(a.tag.begin, "bad NumberOfComponents '" + s.substr(0, 20) + "'");
        return int(c);
    }

    ScalarType typeOf(const ArrayInfo& a)
    {
        ScalarType t;
        const std::string s = attr(a.tag, "type");
        if (!scalarType(s, t))
            in.failAt(a.tag.begin, "unsupported DataArray type '" + s.substr(0, 40) + "'");
        return t;
    }

    uint64_t headerValue(const uint8_t* p) const
    {
        return mHeaderSize == 8 ? loadAs<uint64_t>(p, mBigEndian) : loadAs<uint32_t>(p, mBigEndian);
    }

    /// Binary payload of one array: header (+ block table) followed by data or zlib blocks.
    /// bytes() yields decoded bytes from the array's start; base64 sources decode on demand.
    Payload payload(const ArrayInfo& a, size_t expectedBytes)
    {
        const std::string fmt = attr(a.tag, "format", "ascii");
        const uint8_t* base;
        size_t avail;
        bool base64;
        if (fmt == "appended") {
            if (!mHaveAppended) in.failAt(a.tag.begin, "appended DataArray but no <AppendedData>");
            int64_t off;
            const std::string s = attr(a.tag, "offset");
            if (!parseInt(s.data(), s.data() + s.size(), off) || off < 0 ||
                uint64_t(off) > in.size() - mAppendedStart)
                in.failAt(a.tag.begin, "DataArray offset '" + s.substr(0, 30) +
                                           "' lies outside the appended data");
            base = in.data() + mAppendedStart + off;
            avail = in.size() - mAppendedStart - size_t(off);
            base64 = mAppendedEncoding == "base64";
        } else {
            base = in.data() + a.textBegin;
            avail = a.textEnd - a.textBegin;
            base64 = true;
        }
        // Decoded size needed: header/block table first, then the data that they announce.
        const size_t tableMax = mHeaderSize * 3;
        Payload head = take(base, avail, base64, tableMax, a);
        if (head.size() < mHeaderSize)
            in.failAt(a.tag.begin, "DataArray data ends inside its header");
        size_t total;
        if (mCompressor.empty()) {
            const uint64_t n = headerValue(reinterpret_cast<const uint8_t*>(head.data()));
            if (n != expectedBytes)
                in.failAt(a.tag.begin, "DataArray '" + attr(a.tag, "Name") + "' header says " +
                                           std::to_string(n) + " bytes, expected " +
                                           std::to_string(expectedBytes));
            total = mHeaderSize + expectedBytes;
        } else {
            if (head.size() < tableMax)
                in.failAt(a.tag.begin, "DataArray data ends inside its block table");
            const uint64_t blocks = headerValue(reinterpret_cast<const uint8_t*>(head.data()));
            if (blocks > avail / mHeaderSize)
                in.failAt(a.tag.begin, "absurd zlib block count " + std::to_string(blocks));
            const size_t tableBytes = mHeaderSize * (3 + size_t(blocks));
            head = take(base, avail, base64, tableBytes, a);
            if (head.size() < tableBytes)
                in.failAt(a.tag.begin, "DataArray data ends inside its block table");
            uint64_t compressed = 0;
            for (size_t b = 0; b < blocks; ++b) {
                compressed += headerValue(reinterpret_cast<const uint8_t*>(head.data()) +
                                          mHeaderSize * (3 + b));
                if (compressed > avail) in.failAt(a.tag.begin, "zlib blocks larger than the file");
            }
            total = tableBytes + size_t(compressed);
        }
        Payload all = take(base, avail, base64, total, a);
        if (all.size() < total)
            in.failAt(a.tag.begin, "DataArray '" + attr(a.tag, "Name") + "' is truncated: needs " +
                                       std::to_string(total) + " bytes, " +
                                       std::to_string(all.size()) + " present");
        return all;
    }

    Payload take(const uint8_t* base, size_t avail, bool base64, size_t bytes, const ArrayInfo& a)
    {
        Payload out;
        if (!base64) {
            out.raw = base, out.rawSize = std::min(avail, bytes);
            return out;
        }
        if (!decodeBase64(base, avail, out.decoded, bytes))
            in.failAt(a.tag.begin,
                      "invalid base64 data in DataArray '" + attr(a.tag, "Name") + "'");
        return out;
    }

    void decodeArray(const ArrayInfo& a, uint64_t count, const ScalarType& t,
                     std::vector<float>& fv, std::vector<int64_t>& iv)
    {
        const std::string fmt = attr(a.tag, "format", "ascii");
        if (count > (uint64_t(1) << 40) / t.size) in.failAt(a.tag.begin, "absurd array size");
        if (fmt == "ascii") {
            ByteReader text(in.data(), a.textEnd, mSrc);
            text.seek(a.textBegin);
            const size_t n = text.checkedCount(count, 1, "ASCII values");
            (t.isFloat ? fv.resize(n) : iv.resize(n));
            for (size_t i = 0; i < n; ++i) {
                const double v = readAsciiNumber(text, "DataArray values");
                if (t.isFloat)
                    fv[i] = float(v);
                else
                    iv[i] = int64_t(v);
            }
            return;
        }
        if (fmt != "binary" && fmt != "appended")
            in.failAt(a.tag.begin, "unknown DataArray format '" + fmt.substr(0, 40) + "'");
        const size_t bytes = size_t(count) * t.size;
        const Payload p = payload(a, bytes);
        util::NoInitVector<uint8_t> raw;
        const uint8_t* data = p.data() + mHeaderSize;
        if (!mCompressor.empty()) {
            const uint8_t* h = p.data();
            const uint64_t blocks = headerValue(h), blockSize = headerValue(h + mHeaderSize),
                           lastSize = headerValue(h + 2 * mHeaderSize);
            const uint64_t expect =
                blocks == 0 ? 0 : (blocks - 1) * blockSize + (lastSize ? lastSize : blockSize);
            // (the block size is nominal, often above the data; the product must not wrap)
            if ((blocks > 0 && blockSize == 0) || lastSize > blockSize ||
                (blocks > 1 && blocks - 1 > bytes / blockSize) || expect != bytes)
                in.failAt(a.tag.begin, "zlib blocks of '" + attr(a.tag, "Name") + "' hold " +
                                           std::to_string(expect) + " bytes, expected " +
                                           std::to_string(bytes));
            // Deflate expands at most 1032:1: a header that promises more than its compressed
            // blocks can hold is refused before the output is allocated.
            uint64_t capacity = 0;
            for (uint64_t b = 0; b < blocks; ++b)
                capacity += 1032 * headerValue(h + mHeaderSize * (3 + b)) + 64;
            if (capacity < bytes)
                in.failAt(a.tag.begin, "zlib blocks of '" + attr(a.tag, "Name") + "' (" +
                                           std::to_string(p.size()) + " bytes) cannot inflate to " +
                                           std::to_string(bytes) + " bytes");
            requireMemory(double(bytes) + double(count) * (t.isFloat ? 4 : 8),
                          mSrc + ": DataArray '" + attr(a.tag, "Name") + "'");
            // not zeroed first: the blocks write it, and a table that promises gigabytes of
            // blocks that do not inflate costs the pages of the blocks that did (2.9 GB and
            // up to 34 s before, for a 3 GB promise)
            raw.resize(bytes);
            // the blocks are independent: inflated on all threads, each where the block table
            // puts it; where any fails, the first that does names the error, as in order
            std::vector<size_t> src(size_t(blocks) + 1, mHeaderSize * (3 + size_t(blocks)));
            for (size_t b = 0; b < size_t(blocks); ++b)
                src[b + 1] = src[b] + size_t(headerValue(h + mHeaderSize * (3 + b)));
            const std::string source = mSrc + " (DataArray '" + attr(a.tag, "Name") + "')";
            auto inflateBlock = [&](size_t b) {
                const size_t usize = size_t(b + 1 == blocks && lastSize ? lastSize : blockSize);
                zlibInflate(h + src[b], src[b + 1] - src[b], raw.data() + b * size_t(blockSize),
                            usize, source);
            };
            std::atomic<bool> failed{false};
            tbb::parallel_for(size_t(0), size_t(blocks), [&](size_t b) {
                try {
                    inflateBlock(b);
                } catch (const InputError&) {
                    failed = true;
                }
            });
            for (size_t b = 0; failed && b < size_t(blocks); ++b)
                inflateBlock(b); // throws at the first bad block
            data = raw.data();
        }
        (t.isFloat ? util::resizeInParallel(fv, size_t(count))
                   : util::resizeInParallel(iv, size_t(count)));
        tbb::parallel_for(tbb::blocked_range<size_t>(0, size_t(count), 1 << 15),
                          [&](const tbb::blocked_range<size_t>& r) {
                              for (size_t i = r.begin(); i != r.end(); ++i)
                                  decodeValue(data + i * t.size, t, i, fv, iv);
                          });
    }

    void decodeValue(const uint8_t* q, const ScalarType& t, size_t i, std::vector<float>& fv,
                     std::vector<int64_t>& iv) const
    {
        if (t.isFloat) {
            fv[i] =
                t.size == 4 ? loadAs<float>(q, mBigEndian) : float(loadAs<double>(q, mBigEndian));
            return;
        }
        int64_t v = 0;
        switch (t.size) {
        case 1:
            v = t.isSigned ? int8_t(*q) : *q;
            break;
        case 2:
            v = t.isSigned ? loadAs<int16_t>(q, mBigEndian) : loadAs<uint16_t>(q, mBigEndian);
            break;
        case 4:
            v = t.isSigned ? loadAs<int32_t>(q, mBigEndian) : loadAs<uint32_t>(q, mBigEndian);
            break;
        default:
            v = int64_t(loadAs<uint64_t>(q, mBigEndian));
            break;
        }
        iv[i] = v;
    }

    void append(ParticleSet& into, ParticleSet&& piece, size_t p)
    {
        if (p == 0) {
            into = std::move(piece);
            return;
        }
        if (into.attributes.size() != piece.attributes.size())
            in.fail("pieces carry different point arrays");
        into.positions.insert(into.positions.end(), piece.positions.begin(), piece.positions.end());
        for (Attribute& a : into.attributes) {
            const Attribute* b = piece.find(a.name);
            if (!b || b->type != a.type || b->components != a.components)
                in.fail("pieces carry different point arrays ('" + a.name + "')");
            a.floats.insert(a.floats.end(), b->floats.begin(), b->floats.end());
            a.ints.insert(a.ints.end(), b->ints.begin(), b->ints.end());
        }
    }
};

} // namespace

ParticleSet readVtkXml(const uint8_t* data, size_t size, const std::string& src,
                       std::string* detail)
{
    return VtkXmlParser(data, size, src).parse(detail);
}

} // namespace io_internal
} // namespace fluidsurf
