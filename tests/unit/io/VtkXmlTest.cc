// VTK XML reader: .vtu/.vtp written here in every DataArray encoding VTK produces.
#include "TestData.h"

#include "io/XmlScan.h"

#include <algorithm>
#include <random>

using namespace fluidsurf;
using namespace fluidsurf::test;
using io::ParticleFormat;

namespace {

const std::vector<double> kPoints = {0.5, 1.0, -2.0, 3.25, 4.0, 5.0, -6.0, 7.125, 8.0};
const std::vector<float> kDensity = {998.f, 1000.f, 1002.5f};
const std::vector<int64_t> kIds = {10, 11, 1ll << 40};

std::string rawBytes(const void* p, size_t n)
{
    return std::string(static_cast<const char*>(p), n);
}

struct Encoding
{
    std::string format;   // ascii | binary | appended
    std::string appended; // raw | base64
    bool zlib = false;
    bool header64 = false;
};

/// Payload of one array in the binary encodings: header (+ block table), data or blocks.
std::string payload(const std::string& data, const Encoding& e, size_t blockSize = 16)
{
    ByteBuilder h;
    auto put = [&](uint64_t v) { e.header64 ? h.le(v) : h.le(uint32_t(v)); };
    if (!e.zlib) {
        put(data.size());
        return h.s + data;
    }
    std::vector<std::string> blocks;
    for (size_t i = 0; i < data.size(); i += blockSize)
        blocks.push_back(zlibBytes(data.substr(i, blockSize)));
    put(blocks.size());
    put(blockSize);
    put(data.size() % blockSize);
    for (auto& b : blocks)
        put(b.size());
    std::string out = h.s;
    for (auto& b : blocks)
        out += b;
    return out;
}

std::string makeVtu(const Encoding& e, const std::string& type = "UnstructuredGrid")
{
    const std::string pts = rawBytes(kPoints.data(), kPoints.size() * 8);
    const std::string rho = rawBytes(kDensity.data(), kDensity.size() * 4);
    const std::string ids = rawBytes(kIds.data(), kIds.size() * 8);
    std::string head = "<?xml version=\"1.0\"?>\n<!-- written by a test -->\n<VTKFile type=\"" +
                       type + "\" version=\"1.0\" byte_order=\"LittleEndian\" header_type=\"" +
                       (e.header64 ? "UInt64" : "UInt32") + "\"" +
                       (e.zlib ? " compressor=\"vtkZLibDataCompressor\"" : "") + ">\n<" + type +
                       ">\n<Piece NumberOfPoints=\"3\" NumberOfCells=\"0\">\n";
    std::string appendedData;
    auto array = [&](const std::string& attrs, const std::string& bin, const std::string& ascii) {
        std::string tag = "<DataArray " + attrs + " format=\"" + e.format + "\"";
        if (e.format == "ascii") return tag + ">\n" + ascii + "\n</DataArray>\n";
        const std::string p = payload(bin, e);
        // VTK base64-encodes the block table separately from the compressed blocks.
        const size_t hs = e.header64 ? 8 : 4;
        const size_t table = e.zlib ? hs * (3 + (bin.size() + 15) / 16) : p.size();
        const std::string b64 =
            base64(p.substr(0, table)) + (table < p.size() ? base64(p.substr(table)) : "");
        if (e.format == "binary") return tag + ">\n" + b64 + "\n</DataArray>\n";
        const std::string enc = e.appended == "base64" ? b64 : p;
        tag += " offset=\"" + std::to_string(appendedData.size()) + "\"/>\n";
        appendedData += enc;
        return tag;
    };
    std::string body = "<PointData>\n";
    body += array("type=\"Float32\" Name=\"density\"", rho, "998 1000 1002.5");
    body +=
        array("type=\"Int64\" Name=\"id\" NumberOfComponents=\"1\"", ids, "10 11 1099511627776");
    body += "</PointData>\n<Points>\n";
    body += array("type=\"Float64\" Name=\"Points\" NumberOfComponents=\"3\"", pts,
                  "0.5 1 -2 3.25 4 5\n-6 7.125 8");
    body += "</Points>\n</Piece>\n</" + type + ">\n";
    if (e.format == "appended")
        body += "<AppendedData encoding=\"" + e.appended + "\">\n_" + appendedData +
                "\n</AppendedData>\n";
    return head + body + "</VTKFile>\n";
}

void expectContent(const ParticleSet& ps)
{
    ASSERT_EQ(ps.size(), 3u);
    for (size_t i = 0; i < 3; ++i)
        for (int c = 0; c < 3; ++c)
            EXPECT_EQ(ps.positions[i][c], float(kPoints[i * 3 + c]));
    ASSERT_NE(ps.find("density"), nullptr);
    EXPECT_EQ(ps.find("density")->floats, kDensity);
    ASSERT_NE(ps.find("id"), nullptr);
    EXPECT_EQ(ps.find("id")->ints, kIds);
}

} // namespace

TEST(VtkXml, Ascii)
{
    expectContent(readBytes(makeVtu({"ascii", "", false, false}), ParticleFormat::VtkXml));
}
TEST(VtkXml, InlineBase64)
{
    expectContent(readBytes(makeVtu({"binary", "", false, false}), ParticleFormat::VtkXml));
}
TEST(VtkXml, InlineBase64Zlib)
{
    expectContent(readBytes(makeVtu({"binary", "", true, true}), ParticleFormat::VtkXml));
}
TEST(VtkXml, AppendedRaw)
{
    expectContent(readBytes(makeVtu({"appended", "raw", false, true}), ParticleFormat::VtkXml));
}
TEST(VtkXml, AppendedRawZlib)
{
    expectContent(readBytes(makeVtu({"appended", "raw", true, false}), ParticleFormat::VtkXml));
}
TEST(VtkXml, AppendedBase64)
{
    expectContent(readBytes(makeVtu({"appended", "base64", false, false}), ParticleFormat::VtkXml));
}
TEST(VtkXml, AppendedBase64Zlib)
{
    expectContent(readBytes(makeVtu({"appended", "base64", true, true}), ParticleFormat::VtkXml));
}
TEST(VtkXml, PolyDataVtp)
{
    expectContent(
        readBytes(makeVtu({"appended", "raw", true, false}, "PolyData"), ParticleFormat::VtkXml));
}

TEST(VtkXml, CorruptZlibBlockIsAnError)
{
    std::string f = makeVtu({"appended", "raw", true, false});
    const size_t at = f.find("_") + 40;
    for (size_t i = at; i < at + 8; ++i)
        f[i] = char(~f[i]);
    EXPECT_FALSE(readError(f, ParticleFormat::VtkXml).empty());
}

TEST(VtkXml, UnsupportedCompressorNamed)
{
    std::string f = makeVtu({"appended", "raw", true, false});
    f.replace(f.find("vtkZLibDataCompressor"), 21, "vtkLZ4DataCompressor");
    EXPECT_NE(readError(f, ParticleFormat::VtkXml).find("vtkLZ4DataCompressor"), std::string::npos);
}

namespace {

/// base64 as the VTK XML reader must take it, one character at a time: white space skipped,
/// separately padded quartets one after the other, a bad character or padding out of place
/// refused where it stands, and no more quartets once maxBytes bytes are out.
bool referenceBase64(const std::string& text, size_t maxBytes, std::string& out, size_t& used)
{
    const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    out.clear();
    std::vector<int> quad;
    size_t i = 0;
    for (; i < text.size() && out.size() < maxBytes; ++i) {
        const char c = text[i];
        if (c == ' ' || c == '\n' || c == '\r' || c == '\t' || c == '\f' || c == '\v') continue;
        const size_t v = alphabet.find(c);
        if (v == std::string::npos && c != '=') {
            used = i;
            return false;
        }
        quad.push_back(c == '=' ? -1 : int(v));
        if (quad.size() < 4) continue;
        if (quad[0] < 0 || quad[1] < 0 || (quad[2] < 0 && quad[3] >= 0)) {
            used = i;
            return false;
        }
        const int bytes = quad[2] < 0 ? 1 : quad[3] < 0 ? 2 : 3;
        const long bits = long(quad[0]) << 18 | long(quad[1]) << 12 |
                          long(std::max(quad[2], 0)) << 6 | long(std::max(quad[3], 0));
        for (int b = 0; b < bytes; ++b)
            out += char(bits >> (16 - 8 * b) & 0xff);
        quad.clear();
    }
    used = i;
    return true;
}

} // namespace

TEST(VtkXml, Base64DecodesAsCharacterByCharacter)
{
    // long plain runs (the decoder's quartet-at-once path) broken by white space, padded
    // quartets within the stream, bad characters, short ends, and output limits
    std::mt19937 rng(7);
    const std::string alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    size_t refused = 0, limited = 0;
    for (int trial = 0; trial < 3000; ++trial) {
        std::string text;
        const int pieces = int(rng() % 6) + 1;
        for (int p = 0; p < pieces; ++p) {
            const size_t n = rng() % 90;
            for (size_t k = 0; k < n; ++k)
                text += alphabet[rng() % 64];
            switch (rng() % 8) {
            case 0:
                text += "==";
                break;
            case 1:
                text += "=";
                break;
            case 2:
                text += "\n  ";
                break;
            case 3:
                text += "\r\n";
                break;
            case 4:
                text += (rng() % 20 == 0) ? "*" : "\t";
                break;
            default:
                break;
            }
        }
        const size_t maxBytes = rng() % 4 == 0 ? size_t(rng() % 100) : SIZE_MAX;
        std::string expected, got;
        size_t expectedUsed = 0, gotUsed = 0;
        const bool ok = referenceBase64(text, maxBytes, expected, expectedUsed);
        const bool decoded = io_internal::decodeBase64(
            reinterpret_cast<const uint8_t*>(text.data()), text.size(), got, maxBytes, &gotUsed);
        ASSERT_EQ(decoded, ok) << text;
        ASSERT_EQ(got, expected) << text;
        ASSERT_EQ(gotUsed, expectedUsed) << text;
        refused += !ok, limited += ok && maxBytes != SIZE_MAX && expectedUsed < text.size();
    }
    EXPECT_GT(refused, 100u); // (the cases are all there)
    EXPECT_GT(limited, 100u);
}
