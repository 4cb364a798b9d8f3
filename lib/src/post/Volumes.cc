// Volumes.cc - components and their volumes, and giving volumes back (see Volumes.h).
//
// Sums per component run over fixed chunks of triangles in parallel, each chunk summing runs of
// triangles of one component in order, and the runs are added up in chunk order: the same
// sums for any thread count. Volumes are taken about the mesh's first point, not the origin:
// a frame far from the origin would otherwise add and cancel large terms.
#include "post/Volumes.h"

#include "post/Normals.h"

#include "util/MarkedNumbers.h"
#include "util/Memory.h"
#include "util/Vec3d.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <numeric>

namespace fluidsurf {
namespace post {

namespace {

constexpr size_t kChunk = size_t(1) << 15; ///< triangles per chunk of the sums

/// v's root, halving the path on the way (other threads may be linking and halving too: each
/// store points a node at one of its own ancestors, so every path still ends at the root).
uint32_t root(uint32_t* parent, uint32_t v)
{
    for (;;) {
        uint32_t p = __atomic_load_n(&parent[v], __ATOMIC_RELAXED);
        if (p == v) return v;
        const uint32_t g = __atomic_load_n(&parent[p], __ATOMIC_RELAXED);
        if (g != p)
            __atomic_compare_exchange_n(&parent[v], &p, g, false, __ATOMIC_RELAXED,
                                        __ATOMIC_RELAXED);
        v = g;
    }
}

/// Joins the sets of a and b, the lower root becoming the root of both (lock-free: a root is
/// linked only by a compare-and-swap that finds it still a root). Whatever the order the threads
/// link in, each set ends with its lowest point as its root.
void unite(uint32_t* parent, uint32_t a, uint32_t b)
{
    for (;;) {
        a = root(parent, a), b = root(parent, b);
        if (a == b) return;
        if (a < b) std::swap(a, b); // a: the higher root, to go under b
        uint32_t expected = a;
        if (__atomic_compare_exchange_n(&parent[a], &expected, b, false, __ATOMIC_RELAXED,
                                        __ATOMIC_RELAXED))
            return;
    }
}

/// Per component (by its first corner's), the triangles' signed volume and, if `area`, area.
void sums(const TriangleMesh& mesh, const std::vector<uint32_t>& ofPoint, size_t count,
          std::vector<double>& volume, std::vector<double>* area)
{
    struct Run
    {
        uint32_t component;
        double volume, area;
    };
    const size_t nt = mesh.triangles.size(), chunks = (nt + kChunk - 1) / kChunk;
    const Vec3d o = mesh.points.empty() ? Vec3d(0.0) : toVec3d(mesh.points[0]);
    std::vector<std::vector<Run>> runs(chunks);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, chunks, 1),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t c = r.begin(); c != r.end(); ++c)
                              for (size_t t = c * kChunk; t < std::min(nt, (c + 1) * kChunk); ++t) {
                                  const auto& tri = mesh.triangles[t];
                                  const Vec3d a = toVec3d(mesh.points[tri[0]]) - o,
                                              b = toVec3d(mesh.points[tri[1]]) - o,
                                              d = toVec3d(mesh.points[tri[2]]) - o;
                                  const uint32_t k = ofPoint[tri[0]];
                                  if (runs[c].empty() || runs[c].back().component != k)
                                      runs[c].push_back({k, 0.0, 0.0});
                                  runs[c].back().volume += a.dot(b.cross(d)) / 6;
                                  if (area)
                                      runs[c].back().area += (b - a).cross(d - a).length() / 2;
                              }
                      });
    volume.assign(count, 0.0);
    if (area) area->assign(count, 0.0);
    for (const auto& chunk : runs)
        for (const Run& run : chunk) {
            volume[run.component] += run.volume;
            if (area) (*area)[run.component] += run.area;
        }
}

} // namespace

Components findComponents(const TriangleMesh& mesh)
{
    // On all threads (serial, it was a tenth of post-processing's time on 16 cores): the union
    // is lock-free, each component's root its lowest point, and the components are numbered
    // by their roots in point order, as one thread would number them.
    const size_t nv = mesh.points.size(), nt = mesh.triangles.size();
    std::vector<uint32_t> parent(nv);
    std::iota(parent.begin(), parent.end(), 0u);
    std::vector<uint8_t> used(nv, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nt), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t) {
            const auto& tri = mesh.triangles[t];
            for (int k = 0; k < 3; ++k) {
                __atomic_store_n(&used[tri[k]], uint8_t(1), __ATOMIC_RELAXED);
                unite(parent.data(), tri[k], tri[(k + 1) % 3]);
            }
        }
    });
    Components c;
    c.ofPoint.assign(nv, kNoComponent);
    // the roots numbered in point order
    const util::MarkedNumbers roots(nv, [&](size_t v) { return used[v] && parent[v] == v; });
    roots.forEach([&](size_t v, bool isRoot, size_t k) {
        if (isRoot) c.ofPoint[v] = uint32_t(k - 1);
    });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v)
            if (used[v] && parent[v] != v)
                c.ofPoint[v] = c.ofPoint[root(parent.data(), uint32_t(v))];
    });
    sums(mesh, c.ofPoint, roots.count(), c.volume, nullptr);
    return c;
}

void markClosed(Components& c, const TriangleMesh& mesh, const std::vector<uint32_t>& ofPoint)
{
    // Each side (a, b) is counted at its lower end, among the triangles around that end (the
    // sides a triangle has there: those of its sides whose lower end it is), on all threads:
    // the same counts as sorting every triangle's three sides, as this did (a sort of 2.3M
    // sides and a pass over them on one thread: 50-55 ms of the 13.1M drop's decimation on 2
    // cores, 33-41 ms on 16 threads; now 25-30 and 9-10 ms), for a vertex -> triangle table of
    // half the bytes. (Smoothing builds the same table again for its own use: a few ms.)
    c.closed.assign(c.volume.size(), 1);
    const VertexTriangles around(mesh.triangles, mesh.points.size());
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, mesh.points.size()),
        [&](const tbb::blocked_range<size_t>& r) {
            std::vector<uint32_t> upper; // the other ends of the sides whose lower end is v
            for (size_t v = r.begin(); v != r.end(); ++v) {
                upper.clear();
                for (uint32_t i = around.start[v]; i < around.start[v + 1]; ++i) {
                    // a triangle with v at two corners is listed twice: its sides once
                    if (i > around.start[v] && around.tris[i] == around.tris[i - 1]) continue;
                    const auto& t = mesh.triangles[around.tris[i]];
                    for (int k = 0; k < 3; ++k) {
                        const uint32_t a = t[k], b = t[(k + 1) % 3];
                        if (std::min(a, b) == v) upper.push_back(std::max(a, b));
                    }
                }
                std::sort(upper.begin(), upper.end());
                for (size_t i = 0; i < upper.size();) {
                    size_t j = i;
                    while (j < upper.size() && upper[j] == upper[i])
                        ++j;
                    if (j - i != 2) // (both ends are of one component: the upper one's, as before)
                        __atomic_store_n(&c.closed[ofPoint[upper[i]]], uint8_t(0),
                                         __ATOMIC_RELAXED);
                    i = j;
                }
            }
        });
}

void restoreVolumes(TriangleMesh& mesh, std::vector<uint32_t> ofPoint, const Components& before,
                    double maxOffset, const VertexTriangles& around)
{
    const size_t nv = mesh.points.size(), count = before.volume.size();
    ofPoint.resize(nv, kNoComponent);
    // New points: a triangle neighbour's component, on all threads, pass after pass while some
    // triangle has no corner with one (one pass after Loop steps as a rule: a triangle's
    // children come one after the other, the corner ones first). The steps keep each triangle
    // within one component, so a point's component is the same whichever neighbour gives it,
    // in whatever order. A pass that finds a triangle without one and gives none: those points
    // are not from the components before, and the volumes are left alone.
    uint32_t* const label = ofPoint.data();
    auto load = [&](uint32_t v) { return __atomic_load_n(&label[v], __ATOMIC_RELAXED); };
    const size_t nt = mesh.triangles.size();
    struct Pass
    {
        bool changed = false, missing = false;
    };
    for (;;) {
        const Pass pass = tbb::parallel_reduce(
            tbb::blocked_range<size_t>(0, nt), Pass{},
            [&](const tbb::blocked_range<size_t>& r, Pass p) {
                for (size_t i = r.begin(); i != r.end(); ++i) {
                    const auto& t = mesh.triangles[i];
                    const uint32_t l = std::min({load(t[0]), load(t[1]), load(t[2])});
                    if (l == kNoComponent) {
                        p.missing = true;
                        continue;
                    }
                    for (uint32_t v : t)
                        if (load(v) == kNoComponent)
                            __atomic_store_n(&label[v], l, __ATOMIC_RELAXED), p.changed = true;
                }
                return p;
            },
            [](Pass a, const Pass& b) {
                a.changed |= b.changed, a.missing |= b.missing;
                return a;
            });
        if (!pass.missing) break;
        if (!pass.changed) return; // not from those components after all: leave it
    }
    std::vector<double> volume, area;
    sums(mesh, ofPoint, count, volume, &area);
    std::vector<float> offset(count, 0.f);
    for (size_t c = 0; c < count; ++c)
        if (before.closed.size() == count && before.closed[c] && area[c] > 0)
            offset[c] =
                float(std::clamp((before.volume[c] - volume[c]) / area[c], -maxOffset, maxOffset));
    // along area-weighted normals: a direction is all a first-order offset needs, and they
    // cost no angles (the mesh's own, angle-weighted, come after the move). Kept in
    // mesh.normals meanwhile: fresh buffers the size of the mesh cost more in page faults here
    // than the sums in them.
    util::resizeInParallel(mesh.normals, nv);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v) {
            const Vec3d n = areaNormal(mesh.points, mesh, around, v);
            const double len = n.length();
            mesh.normals[v] = ofPoint[v] != kNoComponent && len > 0
                                  ? toVec3f(n * (offset[ofPoint[v]] / len))
                                  : Vec3f(0, 0, 0);
        }
    });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v)
            mesh.points[v] = mesh.points[v] + mesh.normals[v];
    });
}

} // namespace post
} // namespace fluidsurf
