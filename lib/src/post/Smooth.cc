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

#include <algorithm>

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

    // each point's neighbours, ascending, gathered from its own triangles (in parallel, no
    // global sort): in a closed manifold fan every neighbour is met twice, so one met otherwise
    // marks a border or a non-manifold edge. Point v's are neighbours[2 * corners.start[v] + i],
    // i < count[v].
    const VertexTriangles corners(mesh);
    std::vector<uint32_t> neighbours(2 * corners.tris.size()), count(nv, 0);
    std::vector<uint8_t> fixed(nv, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v) {
            uint32_t* const first = &neighbours[2 * size_t(corners.start[v])];
            uint32_t* last = first;
            for (uint32_t i = corners.start[v]; i < corners.start[v + 1]; ++i)
                for (uint32_t w : mesh.triangles[corners.tris[i]])
                    if (w != v) *last++ = w;
            std::sort(first, last);
            uint32_t* out = first;
            for (uint32_t* w = first; w != last;) {
                uint32_t* run = w;
                while (run != last && *run == *w)
                    ++run;
                if (run - w != 2) fixed[v] = 1;
                *out++ = *w;
                w = run;
            }
            count[v] = uint32_t(out - first);
        }
    });
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
                    if (fixed[v] || count[v] == 0) continue;
                    Vec3d n = normals.normals()[v];
                    const double len = n.length();
                    if (!(len > 0)) continue;
                    n /= len;
                    Vec3d mean(0.0);
                    const uint32_t* const around = &neighbours[2 * size_t(corners.start[v])];
                    for (uint32_t i = 0; i < count[v]; ++i)
                        mean += p[around[i]];
                    mean /= double(count[v]);
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
