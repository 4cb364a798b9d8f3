// PlyIO.cc - PLY point clouds: ascii, binary_little_endian and binary_big_endian; x, y, z as
// float or double; other vertex properties become attributes (properties named base_0, base_1,
// ... are regrouped into one multi-component attribute, which is how the writer stores them).
// Elements before "vertex" (and list properties) are read past; elements after it are ignored.
#include "io/FileBuffer.h"
#include "io/Formats.h"
#include "io/PlyHeader.h"
#include "io/StreamFile.h"
#include "io/TextParse.h"

#include "util/Memory.h"

#include <fluidsurf/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <limits>
#include <optional>

namespace fluidsurf {
namespace io_internal {

namespace {
/// Where a vertex's values lie and which attributes they make: x, y, z, then the other
/// properties, with base_0..base_k-1 runs of one kind (float or int) regrouped.
struct VertexLayout
{
    struct Group
    {
        std::string name;
        size_t first = 0;
        int components = 1;
        bool isFloat = true;
    };
    size_t xyz[3] = {0, 0, 0};
    size_t stride = 0;          ///< bytes of a binary vertex
    std::vector<size_t> offset; ///< of each property within a binary vertex
    std::vector<Group> groups;

    /// InputError (through in) for what the vertex element cannot be.
    VertexLayout(const PlyElement& e, const ByteReader& in) : offset(e.props.size(), 0)
    {
        int found[3] = {-1, -1, -1};
        std::vector<std::string> names;
        for (size_t k = 0; k < e.props.size(); ++k) {
            if (e.props[k].isList)
                in.fail("list property '" + e.props[k].name + "' in vertex element");
            for (int c = 0; c < 3; ++c)
                if (e.props[k].name == std::string(1, char('x' + c))) found[c] = int(k);
            offset[k] = stride;
            stride += e.props[k].type.size;
            names.push_back(e.props[k].name);
        }
        if (found[0] < 0 || found[1] < 0 || found[2] < 0)
            in.fail("vertex element lacks x, y, z properties");
        for (int c = 0; c < 3; ++c)
            xyz[c] = size_t(found[c]);
        for (size_t k = 0; k < names.size();) {
            if (k == xyz[0] || k == xyz[1] || k == xyz[2]) {
                ++k;
                continue;
            }
            Group g;
            size_t run = componentRun(names, k, "_", g.name);
            for (size_t r = 1; r < run; ++r)
                if (e.props[k + r].type.isFloat != e.props[k].type.isFloat)
                    run = 1, g.name = names[k];
            g.first = k;
            g.components = int(run);
            g.isFloat = e.props[k].type.isFloat;
            groups.push_back(g);
            k += run;
        }
    }
};

/// The particles' arrays, sized for n vertices, filled a range of vertices at a time.
struct Vertices
{
    const VertexLayout& layout;
    ParticleSet set;
    std::vector<std::vector<float>> floats;
    std::vector<std::vector<int64_t>> ints;

    Vertices(const VertexLayout& l, size_t n)
        : layout(l), floats(l.groups.size()), ints(l.groups.size())
    {
        util::resizeInParallel(set.positions, n);
        for (size_t g = 0; g < l.groups.size(); ++g)
            (l.groups[g].isFloat ? floats[g].resize(n * l.groups[g].components)
                                 : ints[g].resize(n * l.groups[g].components));
    }
    /// Vertices [first, first + count) on all threads; value(i, k): property k of vertex i.
    template <typename Value> void fill(size_t first, size_t count, const Value& value)
    {
        tbb::parallel_for(tbb::blocked_range<size_t>(first, first + count, 1 << 14),
                          [&](const tbb::blocked_range<size_t>& r) {
                              for (size_t i = r.begin(); i != r.end(); ++i)
                                  fillOne(i, value);
                          });
    }
    template <typename Value> void fillOne(size_t i, const Value& value)
    {
        set.positions[i] = Vec3f(float(value(i, layout.xyz[0])), float(value(i, layout.xyz[1])),
                                 float(value(i, layout.xyz[2])));
        for (size_t g = 0; g < layout.groups.size(); ++g) {
            const VertexLayout::Group& group = layout.groups[g];
            const size_t at = i * size_t(group.components);
            for (int c = 0; c < group.components; ++c)
                if (group.isFloat)
                    floats[g][at + c] = float(value(i, group.first + c));
                else
                    ints[g][at + c] = int64_t(value(i, group.first + c));
        }
    }
    ParticleSet finish()
    {
        for (size_t g = 0; g < layout.groups.size(); ++g) {
            const VertexLayout::Group& group = layout.groups[g];
            if (group.isFloat)
                set.addFloat(group.name, group.components, std::move(floats[g]));
            else
                set.addInt(group.name, group.components, std::move(ints[g]));
        }
        return std::move(set);
    }
};

const char* formatDetail(PlyFormat fmt)
{
    return fmt == PlyFormat::Ascii
               ? "ascii"
               : (fmt == PlyFormat::BigEndian ? "binary big-endian" : "binary little-endian");
}
} // namespace

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
            const VertexLayout layout(e, in);
            const size_t np = e.props.size();
            const size_t n =
                in.checkedCount(e.count, fmt == PlyFormat::Ascii ? 2 * np : stride, "vertices");
            // Property k of vertex i: ascii text is parsed first (in order, one thread), binary
            // values are read where they lie, on all threads. (Every binary value went through
            // an array of doubles first, on one thread: 88 ms and 40 MB for the 1.7M-particle
            // frame's 20 MB PLY on 2 cores.)
            Vertices vertices(layout, n);
            if (fmt == PlyFormat::Ascii) {
                std::vector<double> values(n * np);
                for (size_t i = 0; i < values.size(); ++i) {
                    values[i] = readAsciiNumber(in, "vertex data");
                    if ((i + 1) % np == 0) expectLineEnd(in, "vertex data");
                }
                vertices.fill(0, n, [&](size_t i, size_t k) { return values[i * np + k]; });
            } else {
                const uint8_t* body = in.take(n * stride, "vertex data");
                vertices.fill(0, n, [&](size_t i, size_t k) {
                    return loadPlyNumber(body + i * stride + layout.offset[k], e.props[k].type, be);
                });
            }
            set = vertices.finish();
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
    if (detail) *detail = formatDetail(fmt);
    return set;
}

std::optional<ParticleSet> readPly(const OpenFile& file, const std::string& src,
                                   std::string* detail)
{
    const std::vector<uint8_t> head = file.readHead(size_t(1) << 16);
    ByteReader in(head.data(), head.size(), src);
    PlyHeader header;
    const PlyElement* vertex = nullptr;
    std::optional<VertexLayout> layout;
    uint64_t at = 0; // the vertices' place: after elements of fixed size only
    try {
        header = readPlyHeader(in);
        at = in.offset();
        for (const PlyElement& e : header.elements) {
            uint64_t stride = 0;
            for (const PlyProperty& p : e.props) {
                if (p.isList && e.name != "vertex") return std::nullopt;
                stride += p.type.size;
            }
            const uint64_t left = file.size() - std::min(at, file.size());
            if (e.count > left / std::max<uint64_t>(stride, 1)) return std::nullopt;
            if (e.name == "vertex") {
                vertex = &e;
                layout.emplace(e, in);
                break;
            }
            at += e.count * stride;
        }
    } catch (const InputError&) {
        return std::nullopt; // a longer header, or the message from the whole file
    }
    if (!vertex || header.format == PlyFormat::Ascii) return std::nullopt;
    const bool be = header.format == PlyFormat::BigEndian;
    const size_t n = size_t(vertex->count), stride = layout->stride;
    Vertices vertices(*layout, n);
    forRecordSlices(file, at, n, stride, [&](size_t first, size_t count, const uint8_t* records) {
        for (size_t i = first; i < first + count; ++i)
            vertices.fillOne(i, [&](size_t v, size_t k) {
                return loadPlyNumber(records + (v - first) * stride + layout->offset[k],
                                     vertex->props[k].type, be);
            });
    });
    if (detail) *detail = formatDetail(header.format);
    return vertices.finish();
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
