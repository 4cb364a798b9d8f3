// TextParse.h - whitespace tokenising over a ByteReader for the text formats (legacy VTK
// headers and ASCII data, PLY headers, CSV).
#pragma once

#include "io/ByteReader.h"
#include "io/Formats.h"

#include <string>
#include <vector>

namespace fluidsurf {
namespace io_internal {

inline bool isSpace(uint8_t c)
{
    return c == ' ' || c == '\t' || c == '\n' || c == '\r' || c == '\f' || c == '\v';
}

/// Split a line at whitespace.
inline std::vector<std::string> splitWords(const std::string& line)
{
    std::vector<std::string> words;
    size_t i = 0;
    while (i < line.size()) {
        while (i < line.size() && isSpace(uint8_t(line[i])))
            ++i;
        size_t j = i;
        while (j < line.size() && !isSpace(uint8_t(line[j])))
            ++j;
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
    while (p < n && isSpace(d[p]))
        ++p;
    size_t q = p;
    while (q < n && !isSpace(d[q]))
        ++q;
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

/// After an ASCII record: nothing but blanks up to the end of its line, so a record with a value
/// too many or too few is an error where it is, instead of shifting every record after it.
inline void expectLineEnd(ByteReader& in, const char* what)
{
    const uint8_t* d = in.data();
    size_t p = in.offset();
    while (p < in.size() && (d[p] == ' ' || d[p] == '\t' || d[p] == '\r'))
        ++p;
    if (p < in.size() && d[p] != '\n')
        in.failAt(p,
                  std::string("a line of ") + what + " holds more or fewer values than properties");
    in.seek(p < in.size() ? p + 1 : p);
}

/// Multiply counts from a header, failing (instead of wrapping) on absurd values. In: a
/// ByteReader or a cursor like it (FileCursor).
template <typename In> uint64_t mulChecked(const In& in, uint64_t a, uint64_t b, const char* what)
{
    if (b != 0 && a > (uint64_t(1) << 62) / b) in.fail(std::string("absurd size in ") + what);
    return a * b;
}

/// Parse a non-negative count word from a header.
template <typename In> uint64_t parseCount(const In& in, const std::string& word, const char* what)
{
    int64_t v;
    if (!parseInt(word.data(), word.data() + word.size(), v) || v < 0)
        in.fail(std::string("bad ") + what + " '" + word.substr(0, 40) + "'");
    return uint64_t(v);
}

inline std::string lower(std::string s)
{
    for (char& c : s)
        c = char(std::tolower(uint8_t(c)));
    return s;
}

/// Columns/properties named base<sep>0, base<sep>1, ... (sep one of separators) form one vector
/// attribute. Returns how many names from names[first] on form such a run (1 when none; a run of
/// one is not regrouped), and its base name.
inline size_t componentRun(const std::vector<std::string>& names, size_t first,
                           const char* separators, std::string& base)
{
    auto split = [&](const std::string& n, std::string& b, int& index) {
        const size_t s = n.find_last_of(separators);
        if (s == std::string::npos || s == 0 || s + 1 >= n.size() || n.size() - s > 3) return false;
        index = 0;
        for (size_t i = s + 1; i < n.size(); ++i) {
            if (!std::isdigit(uint8_t(n[i]))) return false;
            index = index * 10 + (n[i] - '0');
        }
        b = n.substr(0, s);
        return true;
    };
    base = names[first];
    std::string b, other;
    int index = 0;
    if (!split(names[first], b, index) || index != 0) return 1;
    size_t run = 1;
    while (first + run < names.size() && split(names[first + run], other, index) && other == b &&
           index == int(run))
        ++run;
    if (run > 1) base = b;
    return run;
}

} // namespace io_internal
} // namespace fluidsurf
