// Smooth.cc - bounded Taubin smoothing along the normals, then the flat regions flattened (see
// Smooth.h).
//
// Why along the normals: the mean of the neighbours also pulls a point sideways on an
// irregular decimated mesh, which thins triangles and does nothing for the bumps. Why mu = -lambda
// rather than Taubin's |mu| > lambda: the pair's transfer (1 - lambda k)(1 + lambda k) is below 1
// for every frequency k, so nothing is inflated; the shrinking of tips that plain Laplacian
// smoothing is known for is held by the bound instead. Each step reads only the last step's
// points (Jacobi), so the result does not depend on the order or the thread count.
#include "post/Smooth.h"

#include "post/Normals.h"
#include "post/SmoothSteps.h"

#include "neighbors/CellIndex.h"

#include "util/Memory.h"
#include "util/Vec3d.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <vector>

namespace fluidsurf {
namespace post {

namespace {

using namespace steps; // (post/SmoothSteps.h: the numbers, shared with the GPU's smoothing)

// Why these numbers (SmoothSteps.h), measured on a jittered slab (J = 0.2-0.4, `fluidsurf_bench
// quality`) and the real frames (BENCHMARKS.md, issue 64): fewer flat steps (kFlatSteps) leave
// the slab's top bumpier (at lambda 0.5: 40 steps 0.79x splashsurf's at J = 0.4, 60: 0.77x, 80:
// 0.76x). The slow part's low pass (kSlowSteps): with the flat steps pulled by curved neighbours
// too, 20 steps (a longer one gave a curved body back less of its volume: hilbert 0.875 of
// N (2r)^3 at 40); with flat neighbours only (flatMean below), no border sag is left to give
// back, and a longer pass gives back less of the jitter's long waves: J = 0.4 at 0.57x with 80
// steps (0.60x with 60, 0.76x with 20), a 4-layer slab 0.66-0.82x (was 0.84-0.97x), hilbert
// still 0.885. With 10 steps on the curvature's copy (kShapeSteps), the jitter still curved
// parts of the slab's top (seed 3: 0.96x at J = 0.4; 20 steps: 0.76x). The flat steps take
// lambda 0.9 (kFlatLambda: a plain Laplacian step's transfer 1 - lambda k stays within (-1, 1]
// for the umbrella's k in [0, 2]): 34 of them do what 60 at 0.5 did (the same figures to
// 0.01x), in less time. kNormalSteps: a flat region's normals turn little in a step (at lambda
// 0.5 the same slab and frames' figures to 0.01x every 6 steps; never again after the first:
// 0.95x at J = 0.4), and the normals were 60% of the flat steps' time. kThinReach 3: the mesh of
// double_dam_break_frame_26 0.49 -> 0.29 voxel from its raw one, as without the flattening; 4
// also made bunny's 0.40 -> 0.42.

template <typename Body> void forEachPoint(size_t n, const Body& body)
{
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v)
            body(v);
    });
}

/// Each point's neighbours, ascending, gathered from its own triangles (in parallel, no global
/// sort): in a closed manifold fan every neighbour is met twice, so one met otherwise marks a
/// border or a non-manifold edge, where the point stays. (The arrays are written whole on all
/// threads before they are read: none is zeroed by one thread first; on 16 cores that was a
/// third of the step.)
struct Rings
{
    VertexTriangles corners;
    util::NoInitVector<uint32_t> neighbours, count;
    util::NoInitVector<uint8_t> fixed;

    explicit Rings(const TriangleMesh& mesh)
        : corners(mesh), neighbours(2 * corners.tris.size()), count(mesh.points.size()),
          fixed(mesh.points.size())
    {
        forEachPoint(mesh.points.size(), [&](size_t v) {
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
        });
    }
    const uint32_t* around(size_t v) const { return &neighbours[2 * size_t(corners.start[v])]; }
    bool moves(size_t v) const { return !fixed[v] && count[v] > 0; }
    /// the mean of v's neighbours' values
    Vec3d mean(const Vec3d* value, size_t v) const
    {
        Vec3d sum(0.0);
        for (uint32_t i = 0; i < count[v]; ++i)
            sum += value[around(v)[i]];
        return sum / double(count[v]);
    }
};

using Points = util::NoInitVector<Vec3d>;

/// Unit normal of v, or false where it has none.
bool unitNormal(const AreaNormals& normals, size_t v, Vec3d& n)
{
    n = normals.normals()[v];
    const double len = n.length();
    if (!(len > 0)) return false;
    n /= len;
    return true;
}

/// to + (at - to) shortened to at most bound
Vec3d within(const Vec3d& at, const Vec3d& to, double bound)
{
    const Vec3d offset = at - to;
    const double dist = offset.length();
    return dist > bound ? to + offset * (bound / dist) : at;
}

/// One Taubin step along the normals of every moving point: p[v] moved by factor of its offset
/// from its neighbours' mean, then held within bound of from[v]; p becomes the result.
void stepAlongNormals(const Rings& rings, AreaNormals& normals, const Points& from, Points& p,
                      Points& next, double factor, double bound)
{
    normals.compute(p.data());
    forEachPoint(p.size(), [&](size_t v) {
        next[v] = p[v];
        Vec3d n;
        if (!rings.moves(v) || !unitNormal(normals, v, n)) return;
        const Vec3d moved = p[v] + n * (factor * n.dot(rings.mean(p.data(), v) - p[v]));
        next[v] = within(moved, from[v], bound);
    });
    std::swap(p, next);
}

/// Marks (kappa = infinity) each point of finite kappa that has another part of the surface
/// facing it within kThinReach voxels: the other side of a sheet, or across a narrow gap (a
/// normal at least 120 degrees from its own; normals from p). Such a sheet is flat but thin, and
/// its particles' bumps are as high as it is thick: the flat steps would eat into it
/// (double_dam_break_frame_26's sheets on its floor, one particle thick, came out half a voxel
/// from the raw mesh). Points already curved are not tested (a third of the time on the 1.7M
/// frame).
void markThin(AreaNormals& normals, const Points& p, double voxel,
              util::NoInitVector<double>& kappa)
{
    const size_t nv = p.size();
    normals.compute(p.data());
    Points unit(nv);
    std::vector<Vec3f> at(nv);
    forEachPoint(nv, [&](size_t v) {
        at[v] = toVec3f(p[v]);
        if (!unitNormal(normals, v, unit[v])) unit[v] = Vec3d(0.0);
    });
    const double reach = kThinReach * voxel;
    Context ctx; // (no progress to report: a fraction of the smoothing)
    const neighbors::CellIndex cells =
        neighbors::buildCellIndex(at.data(), nullptr, nv, reach, ctx);
    forEachPoint(nv, [&](size_t v) {
        const Vec3d& n = unit[v];
        if (!std::isfinite(kappa[v]) || n.lengthSqr() == 0) return;
        bool faced = false;
        const double lo[3] = {p[v].x() - reach, p[v].y() - reach, p[v].z() - reach};
        const double hi[3] = {p[v].x() + reach, p[v].y() + reach, p[v].z() + reach};
        cells.forEachCellInBox(lo, hi, [&](uint32_t begin, uint32_t end) {
            for (uint32_t i = begin; i < end && !faced; ++i) {
                const uint32_t u = cells.order[i];
                faced = unit[u].dot(n) < kFacing && (p[u] - p[v]).lengthSqr() < reach * reach;
            }
        });
        if (faced) kappa[v] = std::numeric_limits<double>::infinity();
    });
}

/// Each point's weight for the flat steps (Smooth.h): 1 where the surface is flat, 0 where it
/// curves or is thin (markThin), from a copy of p smoothed by plain Laplacian steps (on which
/// the particles' bumps are gone and a small droplet is still round: it shrinks towards its
/// middle). Border and unused points count as curved.
util::NoInitVector<double> flatWeights(const Rings& rings, AreaNormals& normals, const Points& p,
                                       double voxel)
{
    const size_t nv = p.size();
    Points shape(nv), next(nv);
    forEachPoint(nv, [&](size_t v) { shape[v] = p[v]; });
    for (int step = 0; step < kShapeSteps; ++step) {
        forEachPoint(nv, [&](size_t v) {
            next[v] = rings.moves(v) ? (shape[v] + rings.mean(shape.data(), v)) * 0.5 : shape[v];
        });
        std::swap(shape, next);
    }
    // curvature 2 |n . (mean - x)| / (mean squared edge): 1/radius on a sphere; infinity where
    // a point counts as curved whatever its shape
    normals.compute(shape.data());
    const double flat = kFlatCurvature / voxel, curved = kCurvedCurvature / voxel;
    util::NoInitVector<double> kappa(nv), spread(nv);
    constexpr double kCurved = std::numeric_limits<double>::infinity();
    forEachPoint(nv, [&](size_t v) {
        Vec3d n;
        kappa[v] = kCurved;
        if (!rings.moves(v) || !unitNormal(normals, v, n)) return;
        double edges = 0;
        for (uint32_t i = 0; i < rings.count[v]; ++i)
            edges += (shape[rings.around(v)[i]] - shape[v]).lengthSqr();
        edges /= double(rings.count[v]);
        if (!(edges > 0)) return;
        const double k = 2 * std::abs(n.dot(rings.mean(shape.data(), v) - shape[v])) / edges;
        if (k < curved) kappa[v] = k; // (past it: weight 0 either way, and no thin test)
    });
    markThin(normals, p, voxel, kappa);
    for (int ring = 0; ring < kFeatureRings; ++ring) {
        forEachPoint(nv, [&](size_t v) {
            double k = kappa[v];
            for (uint32_t i = 0; i < rings.count[v]; ++i)
                k = std::max(k, kappa[rings.around(v)[i]]);
            spread[v] = k;
        });
        std::swap(kappa, spread);
    }
    forEachPoint(nv, [&](size_t v) {
        const double k = kappa[v]; // (infinity: 0)
        spread[v] = k <= flat ? 1 : k >= curved ? 0 : (curved - k) / (curved - flat);
    });
    return spread;
}

/// Points of triangles that the flat steps turned by more than 60 degrees go back to where the
/// flat steps found them (start), until no triangle is left so turned (all back: none). Bumps
/// turn triangles by a few degrees; a sliver of a raw marching-cubes mesh (`--decimate off`)
/// folded over when its corners moved along different normals (a ball's: 4 vertices' normals
/// pointing inwards).
void unfold(const TriangleMesh& mesh, const Rings& rings, const Points& start, Points& p)
{
    const size_t nv = p.size(), nt = mesh.triangles.size();
    // Each triangle tested once, then each moved point told by its own (a point's test of each
    // of its triangles did every triangle's three times: a sixth of the 13.1M drop's smoothing).
    util::NoInitVector<uint8_t> back(nv), turned(nt);
    auto turns = [&](const std::array<uint32_t, 3>& t) {
        if (p[t[0]] == start[t[0]] && p[t[1]] == start[t[1]] && p[t[2]] == start[t[2]])
            return false; // (as it was: not turned)
        const Vec3d before = (start[t[1]] - start[t[0]]).cross(start[t[2]] - start[t[0]]),
                    after = (p[t[1]] - p[t[0]]).cross(p[t[2]] - p[t[0]]);
        return after.dot(before) < kTurned * after.length() * before.length();
    };
    for (bool any = true; any;) {
        forEachPoint(nt, [&](size_t t) { turned[t] = turns(mesh.triangles[t]); });
        any = tbb::parallel_reduce(
            tbb::blocked_range<size_t>(0, nv), false,
            [&](const tbb::blocked_range<size_t>& r, bool found) {
                for (size_t v = r.begin(); v != r.end(); ++v) {
                    back[v] = 0;
                    if (p[v] == start[v]) continue;
                    for (uint32_t i = rings.corners.start[v];
                         i < rings.corners.start[v + 1] && !back[v]; ++i)
                        back[v] = turned[rings.corners.tris[i]];
                    found |= back[v] != 0;
                }
                return found;
            },
            [](bool a, bool b) { return a || b; });
        if (!any) break;
        forEachPoint(nv, [&](size_t v) {
            if (back[v]) p[v] = start[v];
        });
    }
}

void flatten(const TriangleMesh& mesh, const Rings& rings, AreaNormals& normals, const Points& from,
             Points& p, Points& next, const SmoothParams& params)
{
    const size_t nv = p.size();
    const util::NoInitVector<double> weight = flatWeights(rings, normals, p, params.voxel);
    // (the weight squared: a point between flat and curved, on a sheet's bend or near an edge,
    // gains little room)
    auto bound = [&](size_t v) {
        return params.maxMove + (params.flatMove - params.maxMove) * weight[v] * weight[v];
    };
    Points start(nv);
    forEachPoint(nv, [&](size_t v) { start[v] = next[v] = p[v]; });
    // the steps visit only the points they move (weight > 0), each with its own normal from its
    // own triangles (areaNormal: the bits AreaNormals gives): the rest stay the same in both
    // buffers
    std::vector<uint32_t> active;
    for (size_t v = 0; v < nv; ++v)
        if (weight[v] > 0) active.push_back(uint32_t(v)); // (border points weigh 0)
    Points normal(active.size());
    // the mean of a point's flat neighbours only (weight > 0): a flat region does not feel the
    // curved points around it, which lie below its plane where it ends in a rounded edge and
    // would drag its border down (a sag that the slow part then had to give back, with the
    // jitter's long waves)
    auto flatMean = [&](uint32_t v) {
        Vec3d sum(0.0);
        uint32_t count = 0;
        for (uint32_t i = 0; i < rings.count[v]; ++i) {
            const uint32_t u = rings.around(v)[i];
            if (weight[u] > 0) sum += p[u], ++count;
        }
        return count ? sum / double(count) : p[v];
    };
    // (each point's flat neighbours, factor, bound and unit normal made once instead: the same
    // bits and no faster, 0.44 -> 0.46 s on the 13.1M drop's mesh here: the steps wait on
    // memory, 13 MB of points a buffer, not on the loads and divisions that would save)
    for (int step = 0; step < kFlatSteps; ++step) {
        const bool fresh = step % kNormalSteps == 0;
        forEachPoint(active.size(), [&](size_t k) {
            const uint32_t v = active[k];
            if (fresh) normal[k] = areaNormal(p.data(), mesh, rings.corners, v);
            next[v] = p[v];
            const double len = normal[k].length();
            if (!(len > 0)) return;
            const Vec3d n = normal[k] / len;
            const Vec3d moved = p[v] + n * (kFlatLambda * weight[v] * n.dot(flatMean(v) - p[v]));
            next[v] = within(moved, from[v], bound(v));
        });
        std::swap(p, next);
    }
    // the slow part of the moves (a low pass: each step the mean of a point's move and its
    // neighbours' mean move), given back in the share the point moved
    Points moved(nv);
    forEachPoint(nv, [&](size_t v) { moved[v] = p[v] - start[v]; });
    for (int step = 0; step < kSlowSteps; ++step) {
        forEachPoint(nv, [&](size_t v) {
            next[v] = rings.count[v] ? (moved[v] + rings.mean(moved.data(), v)) * 0.5 : moved[v];
        });
        std::swap(moved, next);
    }
    forEachPoint(nv, [&](size_t v) {
        if (rings.moves(v)) p[v] = within(p[v] - moved[v] * weight[v], from[v], bound(v));
    });
    unfold(mesh, rings, start, p);
}

} // namespace

bool smoothingLeaves(const TriangleMesh& mesh, const SmoothParams& params)
{
    const bool flat = params.flatten && params.flatMove > 0 && params.voxel > 0;
    return (params.rounds <= 0 && !flat) || !(params.maxMove > 0) || mesh.triangles.empty();
}

SmoothRings smoothRings(const TriangleMesh& mesh)
{
    Rings r(mesh);
    const size_t nv = mesh.points.size();
    std::vector<uint32_t> start(nv + 1, 0), ring;
    for (size_t v = 0; v < nv; ++v)
        start[v + 1] = start[v] + r.count[v];
    ring.resize(start[nv]);
    forEachPoint(nv,
                 [&](size_t v) { std::copy_n(r.around(v), r.count[v], ring.data() + start[v]); });
    // (the rings read the corners: they go last)
    return SmoothRings{std::move(r.corners), std::move(start), std::move(ring),
                       std::vector<uint8_t>(r.fixed.begin(), r.fixed.end())};
}

TriangleMesh smoothAlongNormals(TriangleMesh mesh, const SmoothParams& params)
{
    const size_t nv = mesh.points.size();
    const bool flat = params.flatten && params.flatMove > 0 && params.voxel > 0;
    if (smoothingLeaves(mesh, params)) return mesh;
    mesh.normals.clear(); // see Normals.h

    const Rings rings(mesh);
    AreaNormals normals(mesh, rings.corners); // cheap, and only their directions matter here
    Points from(nv), p(nv), next(nv);
    forEachPoint(nv, [&](size_t v) { from[v] = p[v] = toVec3d(mesh.points[v]); });
    for (int step = 0; step < 2 * params.rounds; ++step) {
        const double f = step % 2 ? kMu : kLambda;
        stepAlongNormals(rings, normals, from, p, next, f, params.maxMove);
    }
    if (flat) flatten(mesh, rings, normals, from, p, next, params);
    forEachPoint(nv, [&](size_t v) { mesh.points[v] = toVec3f(p[v]); });
    return mesh;
}

TriangleMesh smoothAlongNormals(TriangleMesh mesh, int iterations, double maxMove)
{
    SmoothParams params;
    params.rounds = iterations, params.maxMove = maxMove;
    return smoothAlongNormals(std::move(mesh), params);
}

} // namespace post
} // namespace fluidsurf
