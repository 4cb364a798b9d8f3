// Arrays.cc - checked conversions between NumPy and the library's containers.
#include "Arrays.h"

#include <fluidsurf/Error.h>

#include <cmath>
#include <cstring>
#include <limits>

namespace py = pybind11;

namespace fluidsurf {
namespace python {

namespace {

std::string shapeOf(const py::array& a)
{
    std::string s = "(";
    for (py::ssize_t d = 0; d < a.ndim(); ++d)
        s += (d ? ", " : "") + std::to_string(a.shape(d));
    return s + (a.ndim() == 1 ? ",)" : ")");
}

py::array asArray(py::handle h, const char* name)
{
    if (py::isinstance<py::array>(h)) return py::reinterpret_borrow<py::array>(h);
    // lists and other sequences; ensure() gives a null handle (no exception) for what NumPy
    // cannot make an array of, such as a ragged list, which segfaulted when used
    py::array a;
    try {
        a = py::array::ensure(h);
    } catch (const py::error_already_set&) {
    }
    if (!a)
        throw py::type_error(std::string(name) +
                             " must be an array (or a list of rows of one length, of numbers)");
    return a;
}

bool isFloat(const py::array& a)
{
    return a.dtype().kind() == 'f' && (a.itemsize() == 4 || a.itemsize() == 8);
}

bool isInteger(const py::array& a)
{
    return a.dtype().kind() == 'i' || a.dtype().kind() == 'u';
}

/// A float array of the given rows x cols (cols 0: one dimension), as float32 in C order, with
/// every value finite.
py::array_t<float> floats(py::handle h, const char* name, py::ssize_t rows, py::ssize_t cols)
{
    py::array a = asArray(h, name);
    if (!isFloat(a))
        throw py::type_error(std::string(name) + " must be float32 or float64 (got " +
                             std::string(py::str(a.dtype())) + ")");
    const bool shapeOk = cols == 0 ? a.ndim() == 1 : (a.ndim() == 2 && a.shape(1) == cols);
    if (!shapeOk || (rows >= 0 && a.shape(0) != rows))
        throw ValueError(std::string(name) + " must have shape (" +
                         (rows >= 0 ? std::to_string(rows) : std::string("N")) +
                         (cols ? ", " + std::to_string(cols) + ")" : ",)") + " (got " + shapeOf(a) +
                         ")");
    const py::ssize_t c = cols ? cols : 1;
    auto check = [&](const auto* p) {
        for (py::ssize_t i = 0; i < a.size(); ++i) {
            const double x = double(p[i]);
            if (!std::isfinite(x))
                throw ValueError(std::string(name) + ": row " + std::to_string(i / c) +
                                 " has a non-finite value (" + std::to_string(x) + ")");
            if (std::abs(x) > double(std::numeric_limits<float>::max()))
                throw ValueError(std::string(name) + ": row " + std::to_string(i / c) +
                                 " has a value beyond float32's range (" + std::to_string(x) + ")");
        }
    };
    // checked before rounding to float32, where a large float64 would become inf
    if (a.itemsize() == 8)
        check(py::array_t<double, py::array::c_style | py::array::forcecast>::ensure(a).data());
    auto f = py::array_t<float, py::array::c_style | py::array::forcecast>::ensure(a);
    if (a.itemsize() == 4) check(f.data());
    return f;
}

} // namespace

std::vector<Vec3f> pointsFrom(py::handle array, const char* name)
{
    const auto f = floats(array, name, -1, 3);
    std::vector<Vec3f> points(size_t(f.shape(0)));
    const float* p = f.data();
    for (size_t i = 0; i < points.size(); ++i)
        points[i] = Vec3f(p[3 * i], p[3 * i + 1], p[3 * i + 2]);
    return points;
}

ParticleSet particlesFrom(py::handle positions, py::handle radii, py::handle attributes)
{
    ParticleSet ps;
    ps.positions = pointsFrom(positions, "positions");
    const auto n = py::ssize_t(ps.size());
    ps.attributes = attributesFrom(attributes, ps.size());
    if (!radii.is_none()) {
        const auto r = floats(radii, "radii", n, 0);
        ps.addFloat("pscale", 1, std::vector<float>(r.data(), r.data() + n));
    }
    return ps;
}

std::vector<Attribute> attributesFrom(py::handle attributes, size_t rows)
{
    std::vector<Attribute> out;
    if (attributes.is_none()) return out;
    if (!py::isinstance<py::dict>(attributes))
        throw py::type_error("attributes must be a dict {name: array}");
    const auto n = py::ssize_t(rows);
    ParticleSet ps; // for its checks of names and sizes
    ps.positions.resize(rows);
    for (auto item : py::reinterpret_borrow<py::dict>(attributes)) {
        const std::string name = py::str(item.first);
        const std::string what = "attributes['" + name + "']";
        py::array a = asArray(item.second, what.c_str());
        if (a.ndim() < 1 || a.ndim() > 2 || a.shape(0) != n || (a.ndim() == 2 && a.shape(1) > 16) ||
            (a.ndim() == 2 && a.shape(1) < 1))
            throw ValueError(what + " must have shape (" + std::to_string(n) + ",) or (" +
                             std::to_string(n) + ", k) with k <= 16 (got " + shapeOf(a) + ")");
        const int k = a.ndim() == 2 ? int(a.shape(1)) : 1;
        if (isInteger(a)) {
            auto v = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(a);
            ps.addInt(name, k, std::vector<int64_t>(v.data(), v.data() + v.size()));
        } else if (isFloat(a)) {
            const auto v = floats(a, what.c_str(), n, a.ndim() == 2 ? k : 0);
            ps.addFloat(name, k, std::vector<float>(v.data(), v.data() + v.size()));
        } else {
            throw py::type_error(what + " must be a float or integer array (got " +
                                 std::string(py::str(a.dtype())) + ")");
        }
    }
    return std::move(ps.attributes);
}

py::dict attributesToDict(const std::vector<Attribute>& attributes, size_t rows)
{
    py::dict d;
    for (const Attribute& a : attributes) {
        std::vector<py::ssize_t> shape{py::ssize_t(rows)};
        if (a.components > 1) shape.push_back(a.components);
        if (a.type == AttributeType::Float) {
            py::array_t<float> v(shape);
            if (!a.floats.empty())
                std::memcpy(v.mutable_data(), a.floats.data(), a.floats.size() * sizeof(float));
            d[a.name.c_str()] = v;
        } else {
            py::array_t<int64_t> v(shape);
            if (!a.ints.empty())
                std::memcpy(v.mutable_data(), a.ints.data(), a.ints.size() * sizeof(int64_t));
            d[a.name.c_str()] = v;
        }
    }
    return d;
}

py::dict particlesToDict(const ParticleSet& ps)
{
    py::dict d;
    const auto n = py::ssize_t(ps.size());
    py::array_t<float> p({n, py::ssize_t(3)});
    if (n) std::memcpy(p.mutable_data(), ps.positions.data(), size_t(n) * sizeof(Vec3f));
    d["positions"] = p;
    for (auto item : attributesToDict(ps.attributes, ps.size()))
        d[item.first] = item.second;
    return d;
}

TriangleMesh meshFrom(py::handle vertices, py::handle triangles, py::handle normals)
{
    TriangleMesh m;
    m.points = pointsFrom(vertices, "vertices");
    if (!normals.is_none()) {
        m.normals = pointsFrom(normals, "normals");
        if (m.normals.size() != m.points.size())
            throw ValueError("normals must have one row per vertex (" +
                             std::to_string(m.points.size()) + ", got " +
                             std::to_string(m.normals.size()) + ")");
    }
    py::array t = asArray(triangles, "triangles");
    if (t.ndim() != 2 || t.shape(1) != 3)
        throw ValueError("triangles must have shape (T, 3) (got " + shapeOf(t) + ")");
    if (!isInteger(t))
        throw py::type_error("triangles must be an integer array (got " +
                             std::string(py::str(t.dtype())) + ")");
    auto idx = py::array_t<int64_t, py::array::c_style | py::array::forcecast>::ensure(t);
    m.triangles.resize(size_t(t.shape(0)));
    const int64_t* p = idx.data();
    for (size_t i = 0; i < m.triangles.size(); ++i)
        for (int c = 0; c < 3; ++c) {
            const int64_t v = p[3 * i + size_t(c)];
            if (v < 0 || uint64_t(v) >= m.points.size())
                throw ValueError("triangles: row " + std::to_string(i) + " has index " +
                                 std::to_string(v) + ", outside 0.." +
                                 std::to_string(int64_t(m.points.size()) - 1));
            m.triangles[i][size_t(c)] = uint32_t(v);
        }
    return m;
}

py::array_t<float> view(std::vector<Vec3f>& v, py::handle owner)
{
    static float none[3] = {0, 0, 0}; // numpy wants a pointer even for zero rows
    float* data = v.empty() ? none : &v[0].x;
    return py::array_t<float>({py::ssize_t(v.size()), py::ssize_t(3)},
                              {py::ssize_t(sizeof(Vec3f)), py::ssize_t(sizeof(float))}, data,
                              owner);
}

py::array_t<uint32_t> view(std::vector<std::array<uint32_t, 3>>& v, py::handle owner)
{
    static uint32_t none[3] = {0, 0, 0};
    uint32_t* data = v.empty() ? none : v[0].data();
    return py::array_t<uint32_t>({py::ssize_t(v.size()), py::ssize_t(3)},
                                 {py::ssize_t(3 * sizeof(uint32_t)), py::ssize_t(sizeof(uint32_t))},
                                 data, owner);
}

} // namespace python
} // namespace fluidsurf
