// LoopSubdivision.cc - one Loop subdivision step (see LoopSubdivision.h).
//
// Edges are found by sorting every triangle side by (lower end, upper end, triangle): a stable
// radix sort by the ends of the sides made in triangle order gives one order on every run, and
// each group of equal ends is one edge with its one, two or more triangles. Points are then
// computed in parallel, each from a fixed list of inputs summed in a fixed order.
#include "post/LoopSubdivision.h"

#include "util/Incidence.h"
#include "util/MarkedNumbers.h"
#include "util/Memory.h"
#include "util/RadixSort.h"
#include "util/Vec3d.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cmath>

namespace fluidsurf {
namespace post {

namespace {

/// A triangle's side, its ends in order; sides are sorted by (lo, hi, tri).
struct Side
{
    uint32_t lo, hi, tri;
    uint8_t k; ///< the side runs from corner k to corner k + 1 of its triangle
};

/// `to`, or the point maxMove from `from` on the way there.
Vec3d bounded(const Vec3d& from, const Vec3d& to, double maxMove)
{
    const Vec3d d = to - from;
    const double len = d.length();
    return len > maxMove ? from + d * (maxMove / len) : to;
}

/// Loop's weight of each of n neighbours of a smooth point.
double beta(size_t n)
{
    const double c = 3.0 / 8.0 + std::cos(2.0 * M_PI / double(n)) / 4.0;
    return (5.0 / 8.0 - c * c) / double(n);
}

} // namespace

TriangleMesh loopSubdivide(const TriangleMesh& in, double maxMove)
{
    const size_t nv = in.points.size(), nt = in.triangles.size();
    util::NoInitVector<Side> sides(3 * nt); // (each written below)
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nt), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t)
            for (uint8_t k = 0; k < 3; ++k) {
                const uint32_t a = in.triangles[t][k], b = in.triangles[t][(k + 1) % 3];
                sides[3 * t + k] = {std::min(a, b), std::max(a, b), uint32_t(t), k};
            }
    });
    // by (lo, hi), stably: the sides were made in (triangle, k) order, so equal ends keep
    // triangle order (the comparison sort on all three it replaces gave the same order)
    int bits = 1;
    while (bits < 32 && (uint64_t(1) << bits) < nv)
        ++bits;
    util::radixSortStable(sides, 2 * bits,
                          [&](const Side& e) { return uint64_t(e.lo) << bits | e.hi; });

    // edges: [first[e], first[e + 1]) are its sides; each triangle side's edge
    const size_t ns = sides.size();
    const util::MarkedNumbers edges(ns, [&](size_t i) {
        return i == 0 || sides[i].lo != sides[i - 1].lo || sides[i].hi != sides[i - 1].hi;
    });
    const size_t ne = edges.count();
    util::NoInitVector<uint32_t> first(ne + 1); // (each written below)
    util::NoInitVector<std::array<uint32_t, 3>> sideEdge(nt);
    edges.forEach([&](size_t i, bool starts, size_t e) { // e: edges up to this side's, its own
        if (starts) first[e - 1] = uint32_t(i);
        sideEdge[sides[i].tri][sides[i].k] = uint32_t(e - 1);
    });
    first[ne] = uint32_t(ns);
    auto crease = [&](size_t e) { return first[e + 1] - first[e] != 2; };

    // each point's edges, in edge order
    util::NoInitVector<uint32_t> start, incident;
    util::buildIncidence(
        ne, uint32_t(nv),
        [&](size_t e, auto&& emit) { emit(sides[first[e]].lo), emit(sides[first[e]].hi); }, start,
        incident);

    TriangleMesh out;
    util::resizeInParallel(out.points, nv + ne); // (every one written below)
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v) {
            const Vec3d p = toVec3d(in.points[v]);
            const size_t n = start[v + 1] - start[v];
            size_t creases = 0;
            Vec3d around(0.0), along(0.0);
            for (uint32_t i = start[v]; i < start[v + 1]; ++i) {
                const size_t e = incident[i];
                const Side& s = sides[first[e]];
                const Vec3d q = toVec3d(in.points[s.lo == v ? s.hi : s.lo]);
                around += q;
                if (crease(e)) ++creases, along += q;
            }
            if (n == 0 || creases > 2 || creases == 1)
                out.points[v] = in.points[v]; // unused, a corner of creases, or the end of one
            else if (creases == 2)
                out.points[v] = toVec3f(p * 0.75 + along / 8);
            else
                out.points[v] =
                    toVec3f(bounded(p, p * (1 - double(n) * beta(n)) + around * beta(n), maxMove));
        }
    });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, ne), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t e = r.begin(); e != r.end(); ++e) {
            const Side& s = sides[first[e]];
            const Vec3d ends = toVec3d(in.points[s.lo]) + toVec3d(in.points[s.hi]);
            if (crease(e)) {
                out.points[nv + e] = toVec3f(ends * 0.5);
                continue;
            }
            Vec3d opposite(0.0); // the two corners facing the edge
            for (uint32_t i = first[e]; i < first[e + 1]; ++i)
                opposite += toVec3d(in.points[in.triangles[sides[i].tri][(sides[i].k + 2) % 3]]);
            out.points[nv + e] =
                toVec3f(bounded(ends * 0.5, ends * (3.0 / 8) + opposite / 8, maxMove));
        }
    });
    util::resizeInParallel(out.triangles, 4 * nt);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nt), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t) {
            const auto& [a, b, c] = in.triangles[t];
            const uint32_t ab = uint32_t(nv + sideEdge[t][0]), bc = uint32_t(nv + sideEdge[t][1]),
                           ca = uint32_t(nv + sideEdge[t][2]);
            out.triangles[4 * t + 0] = {a, ab, ca};
            out.triangles[4 * t + 1] = {b, bc, ab};
            out.triangles[4 * t + 2] = {c, ca, bc};
            out.triangles[4 * t + 3] = {ab, bc, ca};
        }
    });
    return out; // without normals: see Normals.h
}

} // namespace post
} // namespace fluidsurf
