// PlyIO.cc - PLY point clouds: ascii, binary_little_endian and binary_big_endian; x, y, z as
// float or double; other vertex properties become attributes (properties named base_0, base_1,
// ... are regrouped into one multi-component attribute, which is how the writer stores them).
// Elements before "vertex" (and list properties) are read past; elements after it are ignored.
#include "io/PlyHeader.h"
#include "io/StreamFile.h"
#include "io/TextParse.h"

#include "util/Memory.h"

#include <fluidsurf/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <limits>

namespace fluidsurf {
namespace io_internal {

ParticleSet readPly(const uint8_t* data, size_t size, const std::string& src, std::string* detail)
{
    ByteReader in(data, size, src);
    const PlyHeader header = readPlyHeader(in);
    const std::vector<PlyElement>& elements = header.elements;
    const PlyFormat fmt = header.format;
    const bool be = fmt == PlyFormat::BigEndian;

    ParticleSet set;
    bool found = false;
    for (const PlyElement& e : elements) {
        const bool isVertex = e.name == "vertex";
        size_t stride = 0;
        bool fixed = true;
        for (const PlyProperty& p : e.props) {
            fixed = fixed && !p.isList;
            stride += p.type.size;
        }
        if (isVertex) {
            if (found) in.fail("second vertex element");
            found = true;
            int ix = -1, iy = -1, iz = -1;
            for (size_t k = 0; k < e.props.size(); ++k) {
                if (e.props[k].isList)
                    in.fail("list property '" + e.props[k].name + "' in vertex element");
                if (e.props[k].name == "x") ix = int(k);
                if (e.props[k].name == "y") iy = int(k);
                if (e.props[k].name == "z") iz = int(k);
            }
            if (ix < 0 || iy < 0 || iz < 0) in.fail("vertex element lacks x, y, z properties");
            const size_t n = in.checkedCount(
                e.count, fmt == PlyFormat::Ascii ? 2 * e.props.size() : stride, "vertices");
            const size_t np = e.props.size();
            // Property k of vertex i: ascii text is parsed first (in order, one thread), binary
            // values are read where they lie, on all threads. (Every binary value went through
            // an array of doubles first, on one thread: 88 ms and 40 MB for the 1.7M-particle
            // frame's 20 MB PLY on 2 cores.)
            std::vector<double> values;
            const uint8_t* body = nullptr;
            std::vector<size_t> offset(np, 0); // within a binary vertex
            if (fmt == PlyFormat::Ascii) {
                values.resize(n * np);
                for (size_t i = 0; i < values.size(); ++i) {
                    values[i] = readAsciiNumber(in, "vertex data");
                    if ((i + 1) % np == 0) expectLineEnd(in, "vertex data");
                }
            } else {
                body = in.take(n * stride, "vertex data");
                for (size_t k = 1; k < np; ++k)
                    offset[k] = offset[k - 1] + e.props[k - 1].type.size;
            }
            auto value = [&](size_t i, size_t k) {
                return body ? loadPlyNumber(body + i * stride + offset[k], e.props[k].type, be)
                            : values[i * np + k];
            };
            auto fill = [&](size_t count, auto&& item) {
                tbb::parallel_for(tbb::blocked_range<size_t>(0, count, 1 << 14),
                                  [&](const tbb::blocked_range<size_t>& r) {
                                      for (size_t i = r.begin(); i != r.end(); ++i)
                                          item(i);
                                  });
            };
            util::resizeInParallel(set.positions, n);
            fill(n, [&](size_t i) {
                set.positions[i] = Vec3f(float(value(i, size_t(ix))), float(value(i, size_t(iy))),
                                         float(value(i, size_t(iz))));
            });
            // Remaining properties, regrouping base_0..base_k-1 runs of one kind (float or int).
            std::vector<std::string> names;
            for (const PlyProperty& prop : e.props)
                names.push_back(prop.name);
            for (size_t k = 0; k < np;) {
                if (int(k) == ix || int(k) == iy || int(k) == iz) {
                    ++k;
                    continue;
                }
                std::string name;
                size_t run = componentRun(names, k, "_", name);
                for (size_t r = 1; r < run; ++r)
                    if (e.props[k + r].type.isFloat != e.props[k].type.isFloat)
                        run = 1, name = names[k];
                const int comps = int(run);
                if (e.props[k].type.isFloat) {
                    std::vector<float> v(n * comps);
                    fill(n, [&](size_t i) {
                        for (int c = 0; c < comps; ++c)
                            v[i * comps + c] = float(value(i, k + c));
                    });
                    set.addFloat(name, comps, std::move(v));
                } else {
                    std::vector<int64_t> v(n * comps);
                    fill(n, [&](size_t i) {
                        for (int c = 0; c < comps; ++c)
                            v[i * comps + c] = int64_t(value(i, k + c));
                    });
                    set.addInt(name, comps, std::move(v));
                }
                k += run;
            }
            break;
        }
        // Skip an element that precedes the vertices.
        if (fmt == PlyFormat::Ascii) {
            const size_t n = in.checkedCount(e.count, 1, "elements");
            for (size_t i = 0; i < n; ++i)
                for (const PlyProperty& p : e.props) {
                    size_t items = 1;
                    if (p.isList)
                        items = in.checkedCount(uint64_t(readAsciiNumber(in, "list count")), 1,
                                                "list items");
                    for (size_t j = 0; j < items; ++j)
                        readAsciiNumber(in, "element data");
                }
        } else if (fixed) {
            in.skip(in.checkedCount(e.count, std::max<size_t>(stride, 1), "elements") * stride,
                    "element data");
        } else {
            const size_t n = in.checkedCount(e.count, 1, "elements");
            for (size_t i = 0; i < n; ++i)
                for (const PlyProperty& p : e.props) {
                    size_t items = 1;
                    if (p.isList)
                        items = size_t(loadPlyNumber(in.take(p.countType.size, "list count"),
                                                     p.countType, be));
                    in.skip(in.checkedCount(items, p.type.size, "list items") * p.type.size,
                            "element data");
                }
        }
    }
    if (!found) in.fail("PLY file has no vertex element");
    if (detail)
        *detail =
            fmt == PlyFormat::Ascii ? "ascii" : (be ? "binary big-endian" : "binary little-endian");
    return set;
}

void writePly(const ParticleSet& ps, io::StreamFile& out)
{
    ps.validate();
    std::string h = "ply\nformat binary_little_endian 1.0\ncomment written by fluidsurf\n";
    h += "element vertex " + std::to_string(ps.size()) + "\n";
    h += "property float x\nproperty float y\nproperty float z\n";
    size_t stride = 12;
    for (const Attribute& a : ps.attributes) {
        if (a.name.empty() || a.name.find_first_of(" \t\r\n") != std::string::npos)
            throw OutputError("attribute name '" + a.name + "' cannot be stored in PLY");
        for (int64_t v : a.ints)
            if (v < std::numeric_limits<int32_t>::min() || v > std::numeric_limits<int32_t>::max())
                throw OutputError("attribute '" + a.name + "' holds " + std::to_string(v) +
                                  ", beyond PLY's int32");
        const char* type = a.type == AttributeType::Float ? "float" : "int";
        for (int c = 0; c < a.components; ++c)
            h += std::string("property ") + type + " " +
                 (a.components > 1 ? a.name + "_" + std::to_string(c) : a.name) + "\n";
        stride += 4 * size_t(a.components);
    }
    h += "end_header\n";
    out.write(h);
    io::writeItems(out, ps.size(), stride, [&](std::string& o, size_t i) {
        o.append(reinterpret_cast<const char*>(&ps.positions[i]), 12);
        for (const Attribute& a : ps.attributes)
            for (int c = 0; c < a.components; ++c) {
                const size_t k = i * a.components + c;
                if (a.type == AttributeType::Float) {
                    o.append(reinterpret_cast<const char*>(&a.floats[k]), 4);
                } else {
                    const int32_t v = int32_t(a.ints[k]); // (in range: checked above)
                    o.append(reinterpret_cast<const char*>(&v), 4);
                }
            }
    });
}

} // namespace io_internal
} // namespace fluidsurf
