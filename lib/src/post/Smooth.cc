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

#include "util/Memory.h"
#include "util/Vec3d.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>

namespace fluidsurf {
namespace post {

namespace {

constexpr double kLambda = 0.5, kMu = -0.5;

} // namespace

TriangleMesh smoothAlongNormals(TriangleMesh mesh, int iterations, double maxMove)
{
    const size_t nv = mesh.points.size();
    if (iterations <= 0 || !(maxMove > 0) || mesh.triangles.empty()) return mesh;
    mesh.normals.clear(); // see Normals.h

    // each point's neighbours, ascending, gathered from its own triangles (in parallel, no
    // global sort): in a closed manifold fan every neighbour is met twice, so one met otherwise
    // marks a border or a non-manifold edge. Point v's are neighbours[2 * corners.start[v] + i],
    // i < count[v].
    // (the arrays here are written whole on all threads before they are read: none is zeroed
    // by one thread first, nor is the mesh copied; on 16 cores that was a third of the step)
    const VertexTriangles corners(mesh);
    util::NoInitVector<uint32_t> neighbours(2 * corners.tris.size()), count(nv);
    util::NoInitVector<uint8_t> fixed(nv);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v) {
            uint32_t* const first = neighbours.data() + 2 * size_t(corners.start[v]);
            uint32_t* last = first;
            fixed[v] = 0;
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
    util::NoInitVector<Vec3d> from(nv), p(nv), next(nv);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v)
            from[v] = p[v] = toVec3d(mesh.points[v]);
    });
    for (int step = 0; step < 2 * iterations; ++step) {
        const double f = step % 2 ? kMu : kLambda;
        normals.compute(p.data());
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
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v)
            mesh.points[v] = toVec3f(p[v]);
    });
    return mesh;
}

} // namespace post
} // namespace fluidsurf
