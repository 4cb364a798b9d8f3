// TextParse.h - whitespace tokenising over a ByteReader for the text formats (legacy VTK
// headers and ASCII data, PLY headers, CSV).
#pragma once

#include "io/ByteReader.h"
#include "io/Formats.h"

#include <string>
#include <vector>

namespace fluidsurf {
namespace io_internal {

inline bool isSpace(uint8_t c) { return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v'; }

/// Split a line at whitespace.
inline std::vector<std::string> splitWords(const std::string& line)
{
    std::vector<std::string> words;
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && isSpace(uint8_t(line[i]))) ++i;
        size_t j = i;
        while (j < line.size() && !isSpace(uint8_t(line[j]))) ++j;
        if (j > i) words.emplace_back(line.substr(i, j - i));
        i = j;
    }
    return words;
}

/// Next whitespace-delimited token as [begin, end) inside the reader's buffer.
inline bool nextToken(ByteReader& in, const char*& begin, const char*& end)
{
    const uint8_t* d = in.data();
    size_t p = in.offset(), n = in.size();
    while (p < n && isSpace(d[p])) ++p;
    size_t q = p;
    while (q < n && !isSpace(d[q])) ++q;
    in.seek(q);
    begin = reinterpret_cast<const char*>(d + p);
    end = reinterpret_cast<const char*>(d + q);
    return q > p;
}

inline double readAsciiNumber(ByteReader& in, const char* what)
{
    const char *b, *e;
    const size_t at = in.offset();
    if (!nextToken(in, b, e)) in.failAt(at, std::string("file ends while reading ") + what);
    double v;
    if (!parseFloat(b, e, v))
        in.failAt(size_t(reinterpret_cast<const uint8_t*>(b) - in.data()),
                  std::string("'") + std::string(b, size_t(std::min<ptrdiff_t>(e - b, 40))) +
                      "' is not a number in " + what);
    return v;
}

/// Multiply counts from a header, failing (instead of wrapping) on absurd values.
inline uint64_t mulChecked(const ByteReader& in, uint64_t a, uint64_t b, const char* what)
{
    if (b != 0 && a > (uint64_t(1) << 62) / b) in.fail(std::string("absurd size in ") + what);
    return a * b;
}

/// Parse a non-negative count word from a header.
inline uint64_t parseCount(const ByteReader& in, const std::string& word, const char* what)
{
    int64_t v;
    if (!parseInt(word.data(), word.data() + word.size(), v) || v < 0)
        in.fail(std::string("bad ") + what + " '" + word.substr(0, 40) + "'");
    return uint64_t(v);
}

inline std::string lower(std::string s)
{
    for (char& c : s) c = char(std::tolower(uint8_t(c)));
    return s;
}

} // namespace io_internal
} // namespace fluidsurf
