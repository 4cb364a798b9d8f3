// CsvReader.cc - delimited text: one particle per line, columns separated by commas, semicolons,
// tabs or spaces; '#' starts a comment line. An optional header names the columns: x/y/z (also
// px.., pos_x.., position_x.., ParaView's "Points:0".."Points:2"); other columns become float
// attributes, with "name_0".. or "name:0".. runs regrouped into one vector attribute. Without a
// header the first three columns are x, y, z and the rest "col3", "col4", ...
#include "io/FileCursor.h"
#include "io/TextParse.h"

#include "util/Memory.h"

#include <fluidsurf/Error.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <charconv>
#include <cstring>

namespace fluidsurf {
namespace io_internal {

bool parseFloat(const char* b, const char* e, double& v)
{
    if (b < e && *b == '+') ++b;
    if (b >= e) return false;
    const auto r = std::from_chars(b, e, v);
    return r.ec == std::errc() && r.ptr == e;
}

bool parseInt(const char* b, const char* e, int64_t& v)
{
    if (b < e && *b == '+') ++b;
    if (b >= e) return false;
    const auto r = std::from_chars(b, e, v);
    return r.ec == std::errc() && r.ptr == e;
}

namespace {

using FieldRanges = std::vector<std::pair<const char*, const char*>>;

/// The fields of the line [b, e) as ranges of its bytes: words for ' ', else split at delim with
/// spaces and quotes trimmed. The one rule for the header line and the data lines alike.
void splitFields(const char* b, const char* e, char delim, FieldRanges& fields)
{
    fields.clear();
    if (delim == ' ') {
        for (const char* i = b; i < e;) {
            while (i < e && isSpace(uint8_t(*i)))
                ++i;
            const char* j = i;
            while (j < e && !isSpace(uint8_t(*j)))
                ++j;
            if (j > i) fields.emplace_back(i, j);
            i = j;
        }
        return;
    }
    for (const char* start = b;;) {
        const char* end = std::find(start, e, delim);
        const char *fb = start, *fe = end;
        while (fb < fe && (isSpace(uint8_t(*fb)) || *fb == '"'))
            ++fb;
        while (fe > fb && (isSpace(uint8_t(fe[-1])) || fe[-1] == '"'))
            --fe;
        fields.emplace_back(fb, fe);
        if (end == e) break;
        start = end + 1;
    }
}

std::vector<std::string> splitFields(const std::string& line, char delim)
{
    FieldRanges ranges;
    splitFields(line.data(), line.data() + line.size(), delim, ranges);
    std::vector<std::string> fields;
    for (const auto& [b, e] : ranges)
        fields.emplace_back(b, e);
    return fields;
}

int axisOf(const std::string& name)
{
    const std::string n = lower(name);
    static const char* kX[] = {"x",        "px",   "pos_x", "position_x",
                               "points:0", "p[0]", "p.x",   "x_coord"};
    static const char* kY[] = {"y",        "py",   "pos_y", "position_y",
                               "points:1", "p[1]", "p.y",   "y_coord"};
    static const char* kZ[] = {"z",        "pz",   "pos_z", "position_z",
                               "points:2", "p[2]", "p.z",   "z_coord"};
    for (const char* k : kX)
        if (n == k) return 0;
    for (const char* k : kY)
        if (n == k) return 1;
    for (const char* k : kZ)
        if (n == k) return 2;
    return -1;
}

/// A text file's bytes: in memory, or in the file, read a piece at a time by the task that
/// parses it (no copy of the whole file).
class TextBytes
{
public:
    TextBytes(const uint8_t* data, size_t size) : mData(data), mSize(size) {}
    explicit TextBytes(const OpenFile& file) : mFile(&file), mSize(size_t(file.size())) {}

    size_t size() const { return mSize; }

    /// The offset just past the first '\n' in [at, limit); limit (or the end) where there is none.
    size_t pastLineEnd(size_t at, size_t limit) const
    {
        limit = std::min(limit, mSize);
        if (mData) {
            const void* nl = std::memchr(mData + at, '\n', limit - at);
            return nl ? size_t(static_cast<const uint8_t*>(nl) - mData) + 1 : limit;
        }
        uint8_t block[1 << 16];
        for (size_t n; at < limit; at += n) {
            n = std::min(sizeof block, limit - at);
            mFile->readAt(at, block, n);
            if (const void* nl = std::memchr(block, '\n', n))
                return at + size_t(static_cast<const uint8_t*>(nl) - block) + 1;
        }
        return limit;
    }

    /// [begin, end): where it lies in memory, or read into buffer.
    const char* bytes(size_t begin, size_t end, std::vector<char>& buffer) const
    {
        if (mData) return reinterpret_cast<const char*>(mData) + begin;
        buffer.resize(end - begin);
        mFile->readAt(begin, buffer.data(), buffer.size());
        return buffer.data();
    }

private:
    const uint8_t* mData = nullptr;
    const OpenFile* mFile = nullptr;
    size_t mSize;
};

/// The data lines after the header, cut into pieces of about 1 MiB at line ends and parsed by
/// all threads: each piece's rows as floats (float(value), as through a double before), its
/// line count, and its first error. The first error in the file is the one named.
class CsvRows
{
public:
    static constexpr size_t kMaxLine = size_t(1) << 20; // ByteReader::line's limit, as before

    CsvRows(const TextBytes& bytes, size_t begin, char delim, size_t columns)
        : mBytes(bytes), mDelim(delim), mColumns(columns)
    {
        const size_t size = bytes.size();
        for (size_t at = begin; at < size;) {
            size_t end = std::min(size, at + (size_t(1) << 20));
            // A line that runs past the limit ends the piece there: it is refused where it
            // starts (the next piece's errors come later in the file), and a file of one endless
            // line is not read whole to find its end.
            if (end < size) end = bytes.pastLineEnd(end, end + kMaxLine + 2);
            mPieces.emplace_back();
            mPieces.back().begin = at, mPieces.back().end = end;
            at = end;
        }
        tbb::parallel_for(size_t(0), mPieces.size(), [&](size_t k) { parse(mPieces[k]); });
    }

    /// Whether a line is bad; the first one's offset and message, numbered from linesBefore + 1.
    bool firstError(size_t linesBefore, size_t& at, std::string& message) const
    {
        size_t line = linesBefore;
        for (const Piece& p : mPieces) {
            if (p.errorAt != SIZE_MAX) {
                at = p.errorAt;
                message = p.errorLine == 0 // no number: a long line
                              ? p.error
                              : "line " + std::to_string(line + p.errorLine) + p.error;
                return true;
            }
            line += p.lines;
        }
        return false;
    }

    size_t rows() const
    {
        size_t n = 0;
        for (const Piece& p : mPieces)
            n += p.values.size() / mColumns;
        return n;
    }

    /// f(first row, the piece's values, row-major) for each piece, on all threads.
    template <typename F> void forPieces(const F& f) const
    {
        std::vector<size_t> first(mPieces.size() + 1, 0);
        for (size_t k = 0; k < mPieces.size(); ++k)
            first[k + 1] = first[k] + mPieces[k].values.size() / mColumns;
        tbb::parallel_for(size_t(0), mPieces.size(),
                          [&](size_t k) { f(first[k], mPieces[k].values); });
    }

private:
    struct Piece
    {
        size_t begin = 0, end = 0;
        size_t lines = 0;
        std::vector<float> values;
        size_t errorAt = SIZE_MAX, errorLine = 0; // errorLine 0: a message without a line number
        std::string error;
    };

    const TextBytes& mBytes;
    char mDelim;
    size_t mColumns;
    std::vector<Piece> mPieces;

    void parse(Piece& p) const
    {
        std::vector<char> buffer;
        const char* d = mBytes.bytes(p.begin, p.end, buffer); // offsets below from p.begin
        const size_t size = p.end - p.begin;
        FieldRanges fields;
        for (size_t at = 0; at < size;) {
            const void* nl = std::memchr(d + at, '\n', size - at);
            const size_t end = nl ? size_t(static_cast<const char*>(nl) - d) : size;
            ++p.lines;
            if (end - at > kMaxLine + 1) {
                p.errorAt = p.begin + at, p.error = "line too long in a text line";
                return;
            }
            const char* b = d + at;
            const char* e = d + end;
            at = end + 1;
            if (e > b && e[-1] == '\r') --e;
            const char* first = b;
            while (first < e && isSpace(uint8_t(*first)))
                ++first;
            if (first == e || *first == '#' || (*first == '/' && e - first > 1 && first[1] == '/'))
                continue;
            splitFields(b, e, mDelim, fields);
            if (fields.size() != mColumns) {
                p.errorAt = p.begin + size_t(b - d), p.errorLine = p.lines;
                p.error = " has " + std::to_string(fields.size()) +
                          " columns, the first data line had " + std::to_string(mColumns);
                return;
            }
            for (const auto& [fb, fe] : fields) {
                double v;
                if (!parseFloat(fb, fe, v)) {
                    p.errorAt = p.begin + size_t(b - d), p.errorLine = p.lines;
                    p.error = ": '" + std::string(fb, std::min<size_t>(size_t(fe - fb), 40)) +
                              "' is not a number";
                    return;
                }
                p.values.push_back(float(v));
            }
        }
    }
};

/// In: a ByteReader over the file in memory, or a FileCursor over the file with bytes reading
/// the same file (the same messages either way).
template <typename In> ParticleSet readCsvFrom(In& in, const TextBytes& bytes, std::string* detail)
{
    const size_t size = in.size();
    // The first content line chooses the delimiter and says whether there is a header; the
    // data lines from there on are parsed on all threads (CsvRows).
    std::vector<std::string> header;
    char delim = ' ';
    size_t columns = 0, lineNo = 0, dataBegin = size;
    while (!in.atEnd()) {
        const size_t at = in.offset();
        const std::string l = in.line("a text line", CsvRows::kMaxLine);
        ++lineNo;
        size_t first = 0;
        while (first < l.size() && isSpace(uint8_t(l[first])))
            ++first;
        if (first == l.size() || l[first] == '#' ||
            (l[first] == '/' && l.size() > first + 1 && l[first + 1] == '/'))
            continue;
        delim = l.find(',') != std::string::npos    ? ','
                : l.find(';') != std::string::npos  ? ';'
                : l.find('\t') != std::string::npos ? '\t'
                                                    : ' ';
        const auto fields = splitFields(l, delim);
        double v;
        const bool numeric =
            !fields.empty() && parseFloat(fields[0].data(), fields[0].data() + fields[0].size(), v);
        columns = fields.size();
        if (!numeric) {
            header = fields;
            dataBegin = in.offset();
        } else {
            if (columns < 3)
                in.failAt(at, "line " + std::to_string(lineNo) + " has " + std::to_string(columns) +
                                  " columns; x, y, z expected");
            dataBegin = at, --lineNo; // the first data line is parsed with the others
        }
        break;
    }
    const CsvRows rows(bytes, dataBegin, delim, std::max<size_t>(columns, 1));
    size_t errorAt;
    std::string error;
    if (rows.firstError(lineNo, errorAt, error)) in.failAt(errorAt, error);
    const size_t n = rows.rows();
    // A header and nothing else is an empty file in a text format's clothes (an empty .xyz
    // is refused the same way): say so, in info too.
    if (n == 0) in.failAt(0, header.empty() ? "no data rows" : "a header and no data rows");
    int axis[3] = {0, 1, 2};
    std::vector<std::string> names(columns);
    for (size_t c = 0; c < columns; ++c)
        names[c] = "col" + std::to_string(c);
    if (!header.empty()) {
        axis[0] = axis[1] = axis[2] = -1;
        for (size_t c = 0; c < columns; ++c) {
            names[c] = header[c];
            const int a = axisOf(header[c]);
            if (a >= 0 && axis[a] < 0) axis[a] = int(c);
        }
        if (axis[0] < 0 || axis[1] < 0 || axis[2] < 0)
            in.failAt(0, "header names no x, y, z columns (found: " + header[0].substr(0, 40) +
                             (columns > 1 ? ", ..." : "") + ")");
    }
    ParticleSet set;
    util::resizeInParallel(set.positions, n);
    rows.forPieces([&](size_t first, const std::vector<float>& v) {
        for (size_t i = 0; i < v.size() / columns; ++i)
            set.positions[first + i] =
                Vec3f(v[i * columns + size_t(axis[0])], v[i * columns + size_t(axis[1])],
                      v[i * columns + size_t(axis[2])]);
    });
    for (size_t c = 0; c < columns;) {
        if (int(c) == axis[0] || int(c) == axis[1] || int(c) == axis[2]) {
            ++c;
            continue;
        }
        std::string base;
        const size_t run = componentRun(names, c, "_:", base);
        std::vector<float> a;
        util::resizeInParallel(a, n * run);
        rows.forPieces([&](size_t first, const std::vector<float>& v) {
            for (size_t i = 0; i < v.size() / columns; ++i)
                for (size_t k = 0; k < run; ++k)
                    a[(first + i) * run + k] = v[i * columns + c + k];
        });
        set.addFloat(base, int(run), std::move(a));
        c += run;
    }
    if (detail) {
        *detail = std::string(delim == ','    ? "comma"
                              : delim == ';'  ? "semicolon"
                              : delim == '\t' ? "tab"
                                              : "space") +
                  "-separated, " + (header.empty() ? "no header" : "header");
    }
    return set;
}

} // namespace

ParticleSet readCsv(const uint8_t* data, size_t size, const std::string& src, std::string* detail)
{
    ByteReader in(data, size, src);
    return readCsvFrom(in, TextBytes(data, size), detail);
}

ParticleSet readCsv(const OpenFile& file, const std::string& src, std::string* detail)
{
    FileCursor in(file, src);
    return readCsvFrom(in, TextBytes(file), detail);
}

} // namespace io_internal
} // namespace fluidsurf
