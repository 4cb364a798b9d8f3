// XmlScan.cc - tag scanning and base64 decoding for the VTK XML reader.
#include "io/XmlScan.h"

#include "io/TextParse.h"

#include <array>
#include <cstdint>

namespace fluidsurf {
namespace io_internal {

bool nextXmlTag(ByteReader& in, XmlTag& tag)
{
    const uint8_t* d = in.data();
    const size_t n = in.size();
    size_t p = in.offset();
    while (true) {
        while (p < n && d[p] != '<')
            ++p;
        if (p >= n) {
            in.seek(n);
            return false;
        }
        if (p + 3 < n && d[p + 1] == '!' && d[p + 2] == '-' && d[p + 3] == '-') {
            // comment: skip to "-->"
            size_t q = p + 4;
            while (q + 2 < n && !(d[q] == '-' && d[q + 1] == '-' && d[q + 2] == '>'))
                ++q;
            if (q + 2 >= n) in.failAt(p, "unterminated XML comment");
            p = q + 3;
            continue;
        }
        if (p + 1 < n && (d[p + 1] == '?' || d[p + 1] == '!')) {
            while (p < n && d[p] != '>')
                ++p;
            if (p >= n) in.failAt(n, "unterminated XML declaration");
            ++p;
            continue;
        }
        break;
    }
    tag = XmlTag();
    tag.begin = p;
    size_t q = p + 1;
    if (q < n && d[q] == '/') {
        tag.isEnd = true;
        ++q;
    }
    size_t s = q;
    while (q < n && !isSpace(d[q]) && d[q] != '>' && d[q] != '/')
        ++q;
    tag.name.assign(reinterpret_cast<const char*>(d + s), q - s);
    if (tag.name.empty()) in.failAt(p, "malformed XML tag");
    while (true) {
        while (q < n && isSpace(d[q]))
            ++q;
        if (q >= n) in.failAt(p, "unterminated XML tag <" + tag.name + ">");
        if (d[q] == '>') {
            ++q;
            break;
        }
        if (d[q] == '/' && q + 1 < n && d[q + 1] == '>') {
            tag.selfClosing = true;
            q += 2;
            break;
        }
        s = q;
        while (q < n && d[q] != '=' && !isSpace(d[q]) && d[q] != '>')
            ++q;
        std::string key(reinterpret_cast<const char*>(d + s), q - s);
        while (q < n && isSpace(d[q]))
            ++q;
        if (q >= n || d[q] != '=')
            in.failAt(q, "malformed attribute '" + key.substr(0, 40) + "' in <" + tag.name + ">");
        ++q;
        while (q < n && isSpace(d[q]))
            ++q;
        if (q >= n || (d[q] != '"' && d[q] != '\''))
            in.failAt(q, "unquoted attribute in <" + tag.name + ">");
        const uint8_t quote = d[q++];
        s = q;
        while (q < n && d[q] != quote)
            ++q;
        if (q >= n) in.failAt(s, "unterminated attribute value in <" + tag.name + ">");
        tag.attrs[key].assign(reinterpret_cast<const char*>(d + s), q - s);
        ++q;
    }
    tag.end = q;
    in.seek(q);
    return true;
}

namespace {
int base64Value(uint8_t c)
{
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    if (c == '+') return 62;
    if (c == '/') return 63;
    if (c == '=') return -2;
    return -1;
}
} // namespace

bool decodeBase64(const uint8_t* text, size_t length, std::string& out, size_t maxBytes,
                  size_t* charsUsed)
{
    // Each character's value, or -1 for anything else (white space, '=' and bad characters
    // take the character-by-character way below).
    static const std::array<int8_t, 256> kValue = [] {
        std::array<int8_t, 256> t{};
        for (int c = 0; c < 256; ++c)
            t[size_t(c)] = int8_t(base64Value(uint8_t(c)) >= 0 ? base64Value(uint8_t(c)) : -1);
        return t;
    }();
    // written in place (a push_back a byte was most of reading a base64 .vtu: 0.58 s for the
    // 1.7M-particle frame's 36 MB on 2 cores); a quartet gives at most 3 bytes
    out.assign(std::min(length / 4 * 3, maxBytes > SIZE_MAX - 2 ? SIZE_MAX : maxBytes + 2), '\0');
    char* o = out.data();
    size_t n = 0;
    auto done = [&](size_t i, bool ok) {
        out.resize(n);
        if (charsUsed) *charsUsed = i;
        return ok;
    };
    int quad[4];
    int k = 0;
    size_t i = 0;
    while (i < length && n < maxBytes) {
        if (k == 0 && i + 4 <= length) { // four plain characters: a quartet at once
            const int a = kValue[text[i]], b = kValue[text[i + 1]], c = kValue[text[i + 2]],
                      d = kValue[text[i + 3]];
            if ((a | b | c | d) >= 0) {
                const uint32_t bits =
                    uint32_t(a) << 18 | uint32_t(b) << 12 | uint32_t(c) << 6 | uint32_t(d);
                o[n] = char(bits >> 16), o[n + 1] = char(bits >> 8), o[n + 2] = char(bits);
                n += 3, i += 4;
                continue;
            }
        }
        const uint8_t c = text[i];
        if (isSpace(c)) {
            ++i;
            continue;
        }
        const int v = base64Value(c);
        if (v == -1) return done(i, false);
        quad[k++] = v;
        if (k < 4) {
            ++i;
            continue;
        }
        k = 0;
        // '=' pads the end of a quad only: x y = = or x y z =. (VTK concatenates separately
        // padded blocks, so a padded quad may be followed by more data.)
        if (quad[0] < 0 || quad[1] < 0 || (quad[2] < 0 && quad[3] >= 0)) return done(i, false);
        const uint32_t bits = (uint32_t(quad[0]) << 18) | (uint32_t(quad[1]) << 12) |
                              (uint32_t(quad[2] < 0 ? 0 : quad[2]) << 6) |
                              uint32_t(quad[3] < 0 ? 0 : quad[3]);
        o[n++] = char(bits >> 16);
        if (quad[2] >= 0) o[n++] = char((bits >> 8) & 0xff);
        if (quad[2] >= 0 && quad[3] >= 0) o[n++] = char(bits & 0xff);
        ++i;
    }
    return done(i, true);
}

} // namespace io_internal
} // namespace fluidsurf
