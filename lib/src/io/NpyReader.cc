// NpyReader.cc - NumPy .npy arrays of shape (N, 3), float32 or float64, either byte order,
// C or Fortran order (format versions 1.0, 2.0 and 3.0). A file is read from where its array lies,
// on all threads, with no copy of the whole file.
#include "io/FileCursor.h"
#include "io/TextParse.h"

#include "util/Memory.h"

#include <fluidsurf/Error.h>

namespace fluidsurf {
namespace io_internal {

namespace {
/// Value of 'key' in the header dict, up to the next top-level ',' or '}'.
std::string dictValue(const std::string& h, const std::string& key)
{
    size_t k = h.find("'" + key + "'");
    if (k == std::string::npos) return "";
    k = h.find(':', k);
    if (k == std::string::npos) return "";
    ++k;
    int depth = 0;
    size_t e = k;
    for (; e < h.size(); ++e) {
        if (h[e] == '(')
            ++depth;
        else if (h[e] == ')')
            --depth;
        else if ((h[e] == ',' || h[e] == '}') && depth == 0)
            break;
    }
    std::string v = h.substr(k, e - k);
    size_t a = 0, b = v.size();
    while (a < b && isSpace(uint8_t(v[a])))
        ++a;
    while (b > a && isSpace(uint8_t(v[b - 1])))
        --b;
    return v.substr(a, b - a);
}

/// In: a ByteReader over the file in memory or a FileCursor over the file (the same messages).
template <typename In> ParticleSet readNpyFrom(In& in, std::string* detail)
{
    if (in.size() < 10) in.failAt(0, "not a NumPy .npy file (missing \\x93NUMPY magic)");
    if (std::memcmp(in.take(6, "magic"), "\x93NUMPY", 6) != 0)
        in.failAt(0, "not a NumPy .npy file (missing \\x93NUMPY magic)");
    const uint8_t major = *in.take(1, "version");
    in.skip(1, "version");
    if (major < 1 || major > 3) in.failAt(6, "unsupported .npy version " + std::to_string(major));
    const size_t headerLen = major == 1 ? in.template read<uint16_t>(false, "header length")
                                        : in.template read<uint32_t>(false, "header length");
    const uint8_t* hp = in.take(headerLen, "header");
    const std::string h(reinterpret_cast<const char*>(hp), headerLen);
    const std::string descr = dictValue(h, "descr");
    const std::string order = dictValue(h, "fortran_order");
    const std::string shape = dictValue(h, "shape");
    size_t item = 0;
    bool big = false;
    if (descr == "'<f4'" || descr == "'=f4'")
        item = 4;
    else if (descr == "'<f8'" || descr == "'=f8'")
        item = 8;
    else if (descr == "'>f4'") {
        item = 4;
        big = true;
    } else if (descr == "'>f8'") {
        item = 8;
        big = true;
    } else
        in.failAt(10, "unsupported dtype " +
                          (descr.empty() ? std::string("(none)") : descr.substr(0, 20)) +
                          " (float32 or float64 expected)");
    if (order != "False" && order != "True") in.failAt(10, "bad fortran_order in header");
    const bool fortran = order == "True";
    // shape "(N, 3)"
    std::vector<std::string> dims;
    if (shape.size() < 2 || shape.front() != '(' || shape.back() != ')')
        in.failAt(10, "bad shape in header");
    {
        std::string cur;
        for (char c : shape.substr(1, shape.size() - 2)) {
            if (c == ',') {
                dims.push_back(cur);
                cur.clear();
            } else if (!isSpace(uint8_t(c)))
                cur += c;
        }
        if (!cur.empty()) dims.push_back(cur);
    }
    if (dims.size() != 2 || dims[1] != "3")
        in.failAt(10, "array shape " + shape.substr(0, 40) + " is not (N, 3)");
    const uint64_t n = parseCount(in, dims[0], "row count");
    const size_t rows = in.checkedCount(n, 3 * item, "rows");
    ParticleSet set;
    util::resizeInParallel(set.positions, rows);
    // value k of the array is row k / 3, axis k % 3 (C order) or axis k / rows, row k % rows
    records(in, 3 * rows, item, "array data", [&](size_t first, size_t n, const uint8_t* p) {
        for (size_t k = first; k != first + n; ++k, p += item) {
            const float v = item == 4 ? loadAs<float>(p, big) : float(loadAs<double>(p, big));
            if (fortran)
                set.positions[k % rows][int(k / rows)] = v;
            else
                set.positions[k / 3][int(k % 3)] = v;
        }
    });
    if (detail)
        *detail =
            std::string(item == 4 ? "float32" : "float64") + (fortran ? ", Fortran order" : "");
    return set;
}
} // namespace

ParticleSet readNpy(const uint8_t* data, size_t size, const std::string& src, std::string* detail)
{
    ByteReader in(data, size, src);
    return readNpyFrom(in, detail);
}

ParticleSet readNpy(const OpenFile& file, const std::string& src, std::string* detail)
{
    FileCursor in(file, src);
    return readNpyFrom(in, detail);
}

} // namespace io_internal
} // namespace fluidsurf
