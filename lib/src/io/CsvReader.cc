// CsvReader.cc - delimited text: one particle per line, columns separated by commas, semicolons,
// tabs or spaces; '#' starts a comment line. An optional header names the columns: x/y/z (also
// px.., pos_x.., position_x.., ParaView's "Points:0".."Points:2"); other columns become float
// attributes, with "name_0".. or "name:0".. runs regrouped into one vector attribute. Without a
// header the first three columns are x, y, z and the rest "col3", "col4", ...
#include "io/TextParse.h"

#include <fluidsurf/Error.h>

#include <charconv>

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

std::vector<std::string> splitFields(const std::string& line, char delim)
{
    std::vector<std::string> f;
    if (delim == ' ') return splitWords(line);
    size_t start = 0;
    while (true) {
        size_t end = line.find(delim, start);
        std::string field =
            line.substr(start, end == std::string::npos ? std::string::npos : end - start);
        // trim spaces and quotes
        size_t a = 0, b = field.size();
        while (a < b && (isSpace(uint8_t(field[a])) || field[a] == '"'))
            ++a;
        while (b > a && (isSpace(uint8_t(field[b - 1])) || field[b - 1] == '"'))
            --b;
        f.push_back(field.substr(a, b - a));
        if (end == std::string::npos) break;
        start = end + 1;
    }
    return f;
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

} // namespace

ParticleSet readCsv(const uint8_t* data, size_t size, const std::string& src, std::string* detail)
{
    ByteReader in(data, size, src);
    // Find the first content line to choose the delimiter and detect a header.
    std::vector<std::string> header;
    char delim = ' ';
    bool delimChosen = false;
    std::vector<double> values;
    size_t columns = 0;
    size_t lineNo = 0;
    while (!in.atEnd()) {
        const size_t at = in.offset();
        const std::string l = in.line("a text line", 1 << 20);
        ++lineNo;
        size_t first = 0;
        while (first < l.size() && isSpace(uint8_t(l[first])))
            ++first;
        if (first == l.size() || l[first] == '#' ||
            (l[first] == '/' && l.size() > first + 1 && l[first + 1] == '/'))
            continue;
        if (!delimChosen) {
            delim = l.find(',') != std::string::npos    ? ','
                    : l.find(';') != std::string::npos  ? ';'
                    : l.find('\t') != std::string::npos ? '\t'
                                                        : ' ';
            delimChosen = true;
        }
        const auto fields = splitFields(l, delim);
        if (columns == 0) {
            double v;
            const bool numeric =
                !fields.empty() &&
                parseFloat(fields[0].data(), fields[0].data() + fields[0].size(), v);
            columns = fields.size();
            if (!numeric) {
                header = fields;
                continue;
            }
            if (columns < 3)
                in.failAt(at, "line " + std::to_string(lineNo) + " has " + std::to_string(columns) +
                                  " columns; x, y, z expected");
        }
        if (fields.size() != columns)
            in.failAt(at, "line " + std::to_string(lineNo) + " has " +
                              std::to_string(fields.size()) + " columns, the first data line had " +
                              std::to_string(columns));
        for (const std::string& f : fields) {
            double v;
            if (!parseFloat(f.data(), f.data() + f.size(), v))
                in.failAt(at, "line " + std::to_string(lineNo) + ": '" + f.substr(0, 40) +
                                  "' is not a number");
            values.push_back(v);
        }
    }
    // A header and nothing else is an empty file in a text format's clothes (an empty .xyz
    // is refused the same way): say so, in info too.
    if (values.empty()) in.failAt(0, header.empty() ? "no data rows" : "a header and no data rows");
    if (columns == 0 && !header.empty()) columns = header.size();
    int axis[3] = {0, 1, 2};
    std::vector<std::string> names(columns);
    for (size_t c = 0; c < columns; ++c)
        names[c] = "col" + std::to_string(c);
    if (!header.empty()) {
        if (header.size() != columns)
            in.fail("header has " + std::to_string(header.size()) + " columns, data " +
                    std::to_string(columns));
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
    const size_t n = columns ? values.size() / columns : 0;
    ParticleSet set;
    set.positions.resize(n);
    for (size_t i = 0; i < n; ++i)
        set.positions[i] =
            Vec3f(float(values[i * columns + axis[0]]), float(values[i * columns + axis[1]]),
                  float(values[i * columns + axis[2]]));
    for (size_t c = 0; c < columns;) {
        if (int(c) == axis[0] || int(c) == axis[1] || int(c) == axis[2]) {
            ++c;
            continue;
        }
        std::string base;
        const size_t run = componentRun(names, c, "_:", base);
        std::vector<float> v(n * run);
        for (size_t i = 0; i < n; ++i)
            for (size_t k = 0; k < run; ++k)
                v[i * run + k] = float(values[i * columns + c + k]);
        set.addFloat(base, int(run), std::move(v));
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

} // namespace io_internal
} // namespace fluidsurf
