// Smooth.cc - bounded Taubin smoothing along the normals (see Smooth.h).
//
// Why along the normals: the mean of the neighbours also pulls a point sideways on an
// irregular decimated mesh, which thins triangles and does nothing for the bumps. Why mu = -lambda
// rather than Taubin's |mu| > lambda: the pair's transfer (1 - lambda k)(1 + lambda k) is below 1
// for every frequency k, so nothing is inflated; the shrinking of tips that plain Laplacian
// smoothing is known for is held by the bound instead. Each step reads only the last step's
// points (Jacobi), so the result does not depend on the order or the thread count.
#include "post/Smooth.h"

#include "post/Normals.h"

#include "util/Vec3d.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

namespace fluidsurf {
namespace post {

namespace {

constexpr double kLambda = 0.5, kMu = -0.5;

} // namespace

TriangleMesh smoothAlongNormals(const TriangleMesh& mesh, int iterations, double maxMove)
{
    TriangleMesh out = mesh;
    const size_t nv = mesh.points.size();
    if (iterations <= 0 || !(maxMove > 0) || mesh.triangles.empty()) return out;

    // neighbours from the directed sides (v, w) of every triangle, both ways: after sorting,
    // each run of one key is an edge, as long as the number of its triangles
    std::vector<uint64_t> sides;
    sides.reserve(6 * mesh.triangles.size());
    for (const auto& t : mesh.triangles)
        for (int k = 0; k < 3; ++k) {
            const uint64_t a = t[k], b = t[(k + 1) % 3];
            sides.push_back(a << 32 | b), sides.push_back(b << 32 | a);
        }
    tbb::parallel_sort(sides.begin(), sides.end());
    std::vector<uint32_t> start(nv + 1, 0), neighbours;
    std::vector<uint8_t> fixed(nv, 0);
    for (size_t i = 0; i < sides.size();) {
        size_t j = i;
        while (j < sides.size() && sides[j] == sides[i])
            ++j;
        const uint32_t v = uint32_t(sides[i] >> 32);
        if (j - i != 2) fixed[v] = 1; // a border or non-manifold edge
        neighbours.push_back(uint32_t(sides[i]));
        ++start[v + 1];
        i = j;
    }
    sides = {};
    for (size_t v = 0; v < nv; ++v)
        start[v + 1] += start[v];

    const VertexTriangles corners(mesh);
    AreaNormals normals(mesh, corners); // cheap, and only their directions matter here
    std::vector<Vec3d> from(nv), p(nv), next(nv);
    for (size_t v = 0; v < nv; ++v)
        from[v] = p[v] = toVec3d(mesh.points[v]);
    for (int step = 0; step < 2 * iterations; ++step) {
        const double f = step % 2 ? kMu : kLambda;
        normals.compute(p);
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
                for (size_t v = r.begin(); v != r.end(); ++v) {
                    next[v] = p[v];
                    if (fixed[v] || start[v] == start[v + 1]) continue;
                    Vec3d n = normals.normals()[v];
                    const double len = n.length();
                    if (!(len > 0)) continue;
                    n /= len;
                    Vec3d mean(0.0);
                    for (uint32_t i = start[v]; i < start[v + 1]; ++i)
                        mean += p[neighbours[i]];
                    mean /= double(start[v + 1] - start[v]);
                    const Vec3d moved = p[v] + n * (f * n.dot(mean - p[v]));
                    const Vec3d offset = moved - from[v];
                    const double dist = offset.length();
                    next[v] = dist > maxMove ? from[v] + offset * (maxMove / dist) : moved;
                }
            });
        std::swap(p, next);
    }
    for (size_t v = 0; v < nv; ++v)
        out.points[v] = toVec3f(p[v]);
    out.normals.clear(); // see Normals.h
    return out;
}

} // namespace post
} // namespace fluidsurf
