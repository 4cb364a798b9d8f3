// Normals.cc - angle-weighted vertex normals (see Normals.h).
//
// Each vertex gathers from its own triangles (a vertex -> triangle table built by counting),
// rather than each triangle scattering into its vertices: no atomics, and the sum runs in the
// same order on every run.
#include "post/Normals.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace fluidsurf {
namespace post {

namespace {

struct V3
{
    double x, y, z;
};

V3 sub(const Vec3f& a, const Vec3f& b)
{
    return {double(a.x) - b.x, double(a.y) - b.y, double(a.z) - b.z};
}

double dot(const V3& a, const V3& b)
{
    return a.x * b.x + a.y * b.y + a.z * b.z;
}

V3 cross(const V3& a, const V3& b)
{
    return {a.y * b.z - a.z * b.y, a.z * b.x - a.x * b.z, a.x * b.y - a.y * b.x};
}

double norm(const V3& a)
{
    return std::sqrt(dot(a, a));
}

} // namespace

void computeAngleWeightedNormals(TriangleMesh& mesh)
{
    const size_t nv = mesh.points.size(), nt = mesh.triangles.size();
    // vertex -> triangles, in triangle order
    std::vector<uint32_t> start(nv + 1, 0), corner(3 * nt);
    for (const auto& t : mesh.triangles)
        for (uint32_t v : t)
            ++start[v + 1];
    for (size_t v = 0; v < nv; ++v)
        start[v + 1] += start[v];
    std::vector<uint32_t> fill(start.begin(), start.end() - 1);
    for (size_t t = 0; t < nt; ++t)
        for (uint32_t v : mesh.triangles[t])
            corner[fill[v]++] = uint32_t(t);
    mesh.normals.assign(nv, Vec3f(0, 0, 0));
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v) {
            V3 sum{0, 0, 0};
            for (uint32_t i = start[v]; i < start[v + 1]; ++i) {
                const auto& t = mesh.triangles[corner[i]];
                const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
                const Vec3f& p = mesh.points[v];
                const V3 a = sub(mesh.points[t[(k + 1) % 3]], p),
                         b = sub(mesh.points[t[(k + 2) % 3]], p);
                const V3 n = cross(a, b);
                const double len = norm(n);
                if (len == 0) continue; // a degenerate triangle has no direction
                const double angle = std::atan2(len, dot(a, b));
                sum.x += angle * n.x / len, sum.y += angle * n.y / len, sum.z += angle * n.z / len;
            }
            const double len = norm(sum);
            if (len > 0)
                mesh.normals[v] = Vec3f(float(sum.x / len), float(sum.y / len), float(sum.z / len));
        }
    });
}

} // namespace post
} // namespace fluidsurf
