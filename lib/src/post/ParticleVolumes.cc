// ParticleVolumes.cc - which component holds each particle, and the components' particle volumes
// (see the header).
//
// Why a ray and not the nearest vertex: a particle deep inside a pool is many voxels from any
// vertex, and one beside a thin sheet is nearer the sheet than the droplet it sits in. Along the
// ray, the crossings that leave the fluid (the triangle's outward normal has a positive x) less
// those that enter it say whether the particle is in the fluid; the closed components crossed an
// odd number of times are those around it, and the first of them crossed, the innermost, holds
// it (a droplet in a cavity of a pool is its own).
#pragma GCC diagnostic ignored "-Wpsabi" // (the lane types never cross a call: see crossings)

#include "post/ParticleVolumes.h"

#include <fluidsurf/Error.h>

#include "post/RayPlanes.h"
#include "util/Lanes.h"
#include "util/Memory.h"
#include "util/RadixSort.h"
#include "util/Vec3d.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <atomic>
#include <cmath>
#include <cstring>
#include <limits>

namespace fluidsurf {
namespace post {

namespace {

/// The axis most of the surface faces (the largest sum of |n_a| area): a surface that runs along
/// the rays puts all its triangles in the few columns it lies in, and flat water does.
int rayAxis(const TriangleMesh& mesh)
{
    struct Sum
    {
        double s[3] = {0, 0, 0};
    };
    // (deterministic: the same chunks added in the same order for any thread count)
    const Sum total = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<size_t>(0, mesh.triangles.size(), 1 << 14), Sum{},
        [&](const tbb::blocked_range<size_t>& r, Sum acc) {
            for (size_t t = r.begin(); t != r.end(); ++t) {
                const auto& tri = mesh.triangles[t];
                const Vec3d a = toVec3d(mesh.points[tri[0]]);
                const Vec3d n =
                    (toVec3d(mesh.points[tri[1]]) - a).cross(toVec3d(mesh.points[tri[2]]) - a);
                for (int k = 0; k < 3; ++k)
                    acc.s[k] += std::fabs(n[k]);
            }
            return acc;
        },
        [](Sum a, const Sum& b) {
            for (int k = 0; k < 3; ++k)
                a.s[k] += b.s[k];
            return a;
        },
        tbb::simple_partitioner());
    return total.s[0] >= total.s[1] && total.s[0] >= total.s[2] ? 0
           : total.s[1] >= total.s[2]                           ? 1
                                                                : 2;
}

void binTriangles(const TriangleMesh& mesh, double cellSize, RayColumns& g)
{
    g.axis = rayAxis(mesh), g.u = (g.axis + 1) % 3, g.v = (g.axis + 2) % 3;
    double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
    for (const Vec3f& p : mesh.points)
        lo[0] = std::min(lo[0], double(p[g.u])), hi[0] = std::max(hi[0], double(p[g.u])),
        lo[1] = std::min(lo[1], double(p[g.v])), hi[1] = std::max(hi[1], double(p[g.v]));
    g.u0 = lo[0], g.v0 = lo[1];
    // at most about 4M columns: the grid's counters stay small whatever the cell
    const double extent = std::max(hi[0] - lo[0], hi[1] - lo[1]);
    g.cell = std::max(cellSize, extent / 2048);
    if (!(g.cell > 0)) g.cell = 1;
    g.nu = g.cellOf(hi[0], g.u0) + 1, g.nv = g.cellOf(hi[1], g.v0) + 1;
    const size_t columns = size_t(g.nu * g.nv);
    auto box = [&](const std::array<uint32_t, 3>& t, int64_t c0[2], int64_t c1[2]) {
        double a[2] = {1e300, 1e300}, b[2] = {-1e300, -1e300};
        for (uint32_t i : t) {
            const Vec3f& p = mesh.points[i];
            a[0] = std::min(a[0], double(p[g.u])), b[0] = std::max(b[0], double(p[g.u]));
            a[1] = std::min(a[1], double(p[g.v])), b[1] = std::max(b[1], double(p[g.v]));
        }
        c0[0] = g.cellOf(a[0], g.u0), c1[0] = g.cellOf(b[0], g.u0);
        c0[1] = g.cellOf(a[1], g.v0), c1[1] = g.cellOf(b[1], g.v0);
    };
    // each column a triangle's box overlaps, f(column); counted and filled on all threads, then
    // each column sorted
    auto forEachColumn = [&](size_t t, auto&& f) {
        int64_t c0[2], c1[2];
        box(mesh.triangles[t], c0, c1);
        for (int64_t y = c0[1]; y <= c1[1]; ++y)
            for (int64_t x = c0[0]; x <= c1[0]; ++x)
                f(size_t(y * g.nu + x));
    };
    std::vector<std::atomic<uint32_t>> count(columns + 1);
    const size_t nt = mesh.triangles.size();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nt, 1 << 14),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t t = r.begin(); t != r.end(); ++t)
                              forEachColumn(t, [&](size_t c) {
                                  count[c + 1].fetch_add(1, std::memory_order_relaxed);
                              });
                      });
    g.start.resize(columns + 1);
    g.start[0] = 0;
    for (size_t c = 0; c < columns; ++c)
        g.start[c + 1] = g.start[c] + count[c + 1].load(std::memory_order_relaxed);
    g.tris.resize(g.start[columns]);
    for (size_t c = 0; c < columns; ++c)
        count[c].store(g.start[c], std::memory_order_relaxed);
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, nt, 1 << 14), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t t = r.begin(); t != r.end(); ++t)
                forEachColumn(t, [&](size_t c) {
                    g.tris[count[c].fetch_add(1, std::memory_order_relaxed)] = uint32_t(t);
                });
        });
    // each column's triangles in mesh order: the crossings of two components at the very same
    // place (a sphere twice) are then met in the same order on every run and every backend, and
    // the first met holds the particle
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, columns, 1 << 10), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t c = r.begin(); c != r.end(); ++c)
                std::sort(g.tris.begin() + g.start[c], g.tris.begin() + g.start[c + 1]);
        });
}

/// The triangles across one column: each one's barycentric s and w and its crossing x as linear
/// functions of the ray's (u, v), taken from the column's corner (small numbers, no cancellation
/// far from the origin). Structure of arrays, padded to a multiple of 4 with planes no ray
/// crosses (s = -1).
struct ColumnPlanes
{
    enum : int { kSu, kSv, kS0, kWu, kWv, kW0, kXa, kXs, kXw, kFields };
    std::vector<double> f[kFields];
    std::vector<uint32_t> comp;
    std::vector<int> sign;
    size_t size = 0;

    void clear()
    {
        for (auto& a : f)
            a.clear();
        comp.clear(), sign.clear(), size = 0;
    }
    void push(const std::array<double, kFields>& values, uint32_t component, int s)
    {
        for (int k = 0; k < kFields; ++k)
            f[k].push_back(values[k]);
        comp.push_back(component), sign.push_back(s), ++size;
    }
    void pad()
    {
        while (f[0].size() % 4)
            for (int k = 0; k < kFields; ++k)
                f[k].push_back(k == kS0 ? -1.0 : 0.0);
    }
};

/// hit(k, x) for each plane k that the ray from (u, v, x0) along the axis crosses ahead (at
/// x > x0), in the planes' order: the lanes of V (util::Doubles, util::WideDoubles) take
/// consecutive planes, with the scalar test's operations in its order (the same bits), and the
/// crossings, a few a ray, are handled one at a time.
template <typename V, typename Hit>
__attribute__((always_inline)) inline void crossings(const ColumnPlanes& p, double u, double v,
                                                     double x0, Hit&& hit)
{
    constexpr size_t L = sizeof(V) / sizeof(double);
    V f[ColumnPlanes::kFields]; // (no lambda: it would not be compiled for the caller's target)
    for (size_t j = 0; j < p.f[0].size(); j += L) {
        for (int k = 0; k < ColumnPlanes::kFields; ++k)
            std::memcpy(&f[k], &p.f[k][j], sizeof f[k]);
        const V s = f[ColumnPlanes::kSu] * u + f[ColumnPlanes::kSv] * v + f[ColumnPlanes::kS0],
                w = f[ColumnPlanes::kWu] * u + f[ColumnPlanes::kWv] * v + f[ColumnPlanes::kW0];
        const auto across = (s >= 0) & (w >= 0) & (s + w <= 1);
        long long any = 0;
        for (size_t l = 0; l < L; ++l)
            any |= across[l];
        if (!any) continue;
        const V x = f[ColumnPlanes::kXa] + s * f[ColumnPlanes::kXs] + w * f[ColumnPlanes::kXw];
        for (size_t l = 0; l < L; ++l)
            if (across[l] && x[l] > x0) hit(j + l, x[l]);
    }
}

template <typename Hit>
__attribute__((target("avx2"))) void wideCrossings(const ColumnPlanes& p, double u, double v,
                                                   double x0, Hit&& hit)
{
    crossings<util::WideDoubles>(p, u, v, x0, hit);
}

} // namespace

RayColumns rayColumns(const TriangleMesh& mesh, const ParticleVolumes& particles, double cellSize)
{
    RayColumns g;
    if (mesh.triangles.empty() || particles.count == 0) return g;
    binTriangles(mesh, cellSize, g);
    const int U = g.u, V = g.v;
    // the ray starts a hair off the particle across it, so that it meets no edge or corner of
    // the mesh (whose points are floats) and crosses each surface exactly once where it does
    g.nudgeU = 1.4142135623e-7 * g.cell, g.nudgeV = 1.7320508075e-7 * g.cell;
    // the particles sorted by column (in input order within one), so that each column's
    // triangles are set up once and stay in cache for all its particles: a stable radix sort of
    // (column, particle) on all threads (a counting sort on one thread took 0.3 s of the 13.1M
    // drop's 0.54 s here on an H200 host's 16 threads; on 2 cores the two cost the same)
    const size_t columns = g.start.size() - 1;
    util::NoInitVector<uint64_t> keyed(particles.count); // column << 32 | particle
    tbb::parallel_for(tbb::blocked_range<size_t>(0, particles.count, 1 << 14),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i) {
                              const Vec3f& q = particles.positions[i];
                              const int64_t cu = g.cellOf(double(q[U]) + g.nudgeU, g.u0),
                                            cv = g.cellOf(double(q[V]) + g.nudgeV, g.v0);
                              const bool in = cu >= 0 && cv >= 0 && cu < g.nu && cv < g.nv;
                              // (outside every column: sorted last, as column `columns`)
                              keyed[i] = uint64_t(in ? size_t(cv * g.nu + cu) : columns) << 32 | i;
                          }
                      });
    int keyBits = 1;
    while ((uint64_t(1) << keyBits) <= columns)
        ++keyBits;
    util::radixSortStable(keyed, keyBits, [](uint64_t k) { return k >> 32; });
    // first[c]: where column c's particles begin, written by the first of them for it and the
    // empty columns before it; then the particles' numbers alone
    const size_t n = keyed.size();
    g.first.resize(columns + 1);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n + 1, 1 << 14),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t k = r.begin(); k != r.end(); ++k) {
                              const size_t from = k == 0 ? 0 : size_t(keyed[k - 1] >> 32) + 1,
                                           to = k == n ? columns : size_t(keyed[k] >> 32);
                              for (size_t c = from; c <= to && c <= columns; ++c)
                                  g.first[c] = uint32_t(k);
                          }
                      });
    util::resizeInParallel(g.sorted, g.first[columns]);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, g.sorted.size(), 1 << 14),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t k = r.begin(); k != r.end(); ++k)
                              g.sorted[k] = uint32_t(keyed[k]);
                      });
    return g;
}

std::vector<uint32_t> componentsOfParticles(const TriangleMesh& mesh,
                                            const std::vector<uint32_t>& ofPoint,
                                            const Components& c, const ParticleVolumes& particles,
                                            double cellSize, int lanes)
{
    if (lanes == 0) lanes = util::doubleRegisterLanes();
    if (lanes != 2 && lanes != 4)
        throw ValueError("componentsOfParticles: 2 or 4 doubles a register");
    if (lanes > util::doubleRegisterLanes())
        throw ValueError("componentsOfParticles: 4 doubles a register need a CPU with AVX2");
    std::vector<uint32_t> out(particles.count, kNoComponent);
    if (mesh.triangles.empty() || particles.count == 0) return out;
    const RayColumns g = rayColumns(mesh, particles, cellSize);
    const int A = g.axis, U = g.u, V = g.v;
    const double nudgeU = g.nudgeU, nudgeV = g.nudgeV;
    const size_t columns = g.start.size() - 1;
    const std::vector<uint32_t>& first = g.first;
    const std::vector<uint32_t>& sorted = g.sorted;
    const bool wide = lanes == 4;
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, columns, 64), [&](const tbb::blocked_range<size_t>& r) {
            struct Crossing
            {
                uint32_t comp;
                int count;
                double nearest;
            };
            std::vector<Crossing> crossed;
            ColumnPlanes planes;
            for (size_t col = r.begin(); col != r.end(); ++col) {
                if (first[col] == first[col + 1] || g.start[col] == g.start[col + 1]) continue;
                const double cu0 = g.cornerU(col), cv0 = g.cornerV(col);
                planes.clear();
                for (uint32_t k = g.start[col]; k < g.start[col + 1]; ++k) {
                    const auto& t = mesh.triangles[g.tris[k]];
                    const uint32_t comp = ofPoint[t[0]];
                    if (comp == kNoComponent) continue;
                    double corner[3][3];
                    for (int j = 0; j < 3; ++j)
                        for (int a = 0; a < 3; ++a)
                            corner[j][a] = double(mesh.points[t[j]][a]);
                    RayPlane p;
                    int sign;
                    if (!rayPlane(corner[0], corner[1], corner[2], cu0, cv0, A, U, V, p, sign))
                        continue; // edge-on to the ray
                    planes.push({p.su, p.sv, p.s0, p.wu, p.wv, p.w0, p.xa, p.xs, p.xw}, comp, sign);
                }
                planes.pad();
                for (uint32_t at = first[col]; at < first[col + 1]; ++at) {
                    const size_t i = sorted[at];
                    const Vec3f& q = particles.positions[i];
                    const double u = double(q[U]) + nudgeU - cu0, v = double(q[V]) + nudgeV - cv0,
                                 x0 = double(q[A]);
                    crossed.clear();
                    int winding = 0; // leaving crossings less entering ones ahead: 1 inside
                    auto hit = [&](size_t k, double x) {
                        winding += planes.sign[k];
                        const uint32_t comp = planes.comp[k];
                        auto it = std::find_if(crossed.begin(), crossed.end(),
                                               [&](const Crossing& c) { return c.comp == comp; });
                        if (it == crossed.end())
                            crossed.push_back({comp, 1, x});
                        else
                            ++it->count, it->nearest = std::min(it->nearest, x);
                    };
                    if (wide)
                        wideCrossings(planes, u, v, x0, hit);
                    else
                        crossings<util::Doubles>(planes, u, v, x0, hit);
                    if (winding <= 0) continue; // outside the fluid (or in a cavity of it)
                    // the components around the particle are those the ray crosses an odd
                    // number of times; of the outward ones (a cavity's faces point in: negative
                    // volume) the innermost, crossed first
                    double nearest = std::numeric_limits<double>::infinity();
                    for (const Crossing& cr : crossed)
                        if ((cr.count & 1) && c.volume[cr.comp] > 0 && cr.nearest < nearest)
                            nearest = cr.nearest, out[i] = cr.comp;
                }
            }
        });
    return out;
}

size_t useParticleVolumes(Components& c, const std::vector<uint32_t>& of,
                          const ParticleVolumes& particles)
{
    std::vector<double> sum(c.volume.size(), 0.0);
    for (size_t i = 0; i < of.size(); ++i) {
        if (of[i] == kNoComponent) continue;
        const double d = 2 * (particles.radii ? double(particles.radii[i]) : particles.radius);
        sum[of[i]] += d * d * d;
    }
    size_t changed = 0;
    for (size_t k = 0; k < sum.size(); ++k)
        if (sum[k] > 0) c.volume[k] = c.volume[k] > 0 ? sum[k] : -sum[k], ++changed;
    return changed;
}

std::vector<Vec3f> centresOutside(const std::vector<uint32_t>& of, const ParticleVolumes& particles)
{
    std::vector<Vec3f> out;
    const uint32_t *skip = particles.isolated, *skipEnd = skip + particles.isolatedCount;
    for (size_t i = 0; i < of.size(); ++i) {
        while (skip != skipEnd && *skip < i)
            ++skip;
        if (of[i] != kNoComponent || (skip != skipEnd && *skip == i)) continue;
        out.push_back(particles.positions[i]);
    }
    return out;
}

} // namespace post
} // namespace fluidsurf
