// Decimate.cc - parallel quadric-error decimation (see Decimate.h).
//
// Why our own and not OpenMesh's Decimater (post/OpenMeshDecimate, kept as the baseline and as
// `--decimator openmesh`): the Decimater is serial, with a half-edge mesh and a heap of 15 us a
// collapse here, while the raw meshes have millions of triangles. Greedy collapse is
// inherently ordered, so the parallel form keeps the order where it matters, locally:
//
// - The mesh is cut into cubes ("blocks") of about kBlockEdges mean edge lengths, each triangle
//   in the block of its centroid. A vertex whose triangles all lie in one block is owned by it;
//   a block collapses only edges between vertices it owns, cheapest first (its own heap). Such
//   a collapse touches only the block's triangles and owned points, so blocks run concurrently
//   without locks, and each block's work depends on nothing but its own input: the result is
//   the same for any thread count.
// - A pass runs every block once; the next pass shifts the blocks by half a block, so that the
//   last pass's borders lie inside a block. Passes repeat until the target is reached.
// - The order across blocks comes from a shared error threshold per pass: the k-th smallest
//   collapse error (from a sample of the edges), k a few times the collapses still needed, so
//   that cheap collapses everywhere go before dear ones anywhere (flat bumps first, as the
//   thesis wants). The collapses still needed are shared out between blocks in proportion to
//   their edges under the threshold, so a pass never overshoots a triangle target; the last
//   tenth go to the blocks by size, cheapest first in each.
// - Why not one serial heap (the textbook greedy): measured on the real frames, it pulled thin
//   tips in by 2-4 voxels whatever the weights or placement, where the passes keep them.
//
// Each collapse moves the edge to the point of least quadric error (not to one of its ends, as
// OpenMesh does): the error is measured against the original triangles' planes, which averages
// out the particles' bumps on flat fluid. Guards refuse a collapse that would
// - break manifoldness: the ends must share exactly the two neighbours across the edge (the
//   link condition), and no vertex may be left with fewer than three triangles;
// - turn a remaining triangle's normal by more than kMaxTurnDegrees (a fold or flip);
// - leave a triangle thinner than kMinQuality that was not already thinner (slivers);
// - carry a vertex farther from the input than DecimateTarget::maxDrift (see State::drift).
#include "post/Decimate.h"

#include "post/Normals.h"
#include "post/Quadric.h"

#include "util/TriangleDistance.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <queue>

namespace fluidsurf {
namespace post {

namespace {

using Tri = std::array<uint32_t, 3>;

constexpr double kBlockEdges = 32;     ///< a block's side in mean edge lengths (~2,500 triangles)
constexpr double kMaxTurnDegrees = 60; ///< the most a remaining triangle's normal may turn
constexpr double kMinQuality = 0.25;   ///< 4 sqrt3 area / sum of squared sides; ~10 deg at 0.25
constexpr size_t kMaxPasses = 64;
constexpr size_t kLastShare = 10; ///< see "last" in decimate()
constexpr size_t kSample = 4;     ///< a pass' threshold from every kSample-th triangle's edges
constexpr size_t kMaxFan = 64;    ///< vertices with more triangles are left alone

const double kMaxTurnCos = std::cos(kMaxTurnDegrees * M_PI / 180);

/// The whole mesh between passes, points relative to the middle of its bounds so that the
/// quadrics' constants stay small and their errors exact to many digits.
struct State
{
    Vec3d middle{0.0}; ///< of the input's bounds
    std::vector<Vec3d> points;
    std::vector<Quadric> quadrics;
    /// How far each vertex may be from the input surface it stands for: 0 for an input vertex;
    /// a collapse adds its point's largest distance to the planes of the triangles it replaces
    /// to the larger drift of its two ends (an upper bound along the normals, where the
    /// quadric's mean can hide a tip pulled in by a few voxels).
    std::vector<float> drift;
    std::vector<Tri> triangles;
};

struct Collapse
{
    Vec3d point;
    double error; ///< area-weighted mean squared distance to the planes
};

Collapse bestCollapse(const State& s, uint32_t a, uint32_t b)
{
    const Quadric q = s.quadrics[a] + s.quadrics[b];
    const Vec3d p = q.minimizer((s.points[a] + s.points[b]) * 0.5);
    return {p, q.w > 0 ? q.error(p) / q.w : 0.0};
}

/// 1 for an equilateral triangle, 0 for a degenerate one.
double quality(const Vec3d& a, const Vec3d& b, const Vec3d& c)
{
    const double sides = (b - a).lengthSqr() + (c - b).lengthSqr() + (a - c).lengthSqr();
    return sides > 0 ? 2 * std::sqrt(3.0) * (b - a).cross(c - a).length() / sides : 0;
}

struct BlockResult
{
    std::vector<Tri> triangles; ///< what is left of the block's triangles
    size_t collapses = 0, refused = 0;
    double maxError = 0, maxDrift = 0;
};

/// One block's greedy collapses (see the top of the file). Reads the points and quadrics of
/// every vertex of its triangles, writes only those of the vertices it owns.
class Block
{
public:
    Block(State& s, const uint32_t* tris, size_t n, const std::vector<uint32_t>& valence) : mS(s)
    {
        // local vertices in ascending mesh order, from one sort of (vertex, corner) keys
        std::vector<uint64_t> corners(3 * n);
        for (size_t i = 0; i < n; ++i)
            for (int k = 0; k < 3; ++k)
                corners[3 * i + k] = uint64_t(s.triangles[tris[i]][k]) << 32 | (3 * i + k);
        std::sort(corners.begin(), corners.end());
        mTris.resize(n);
        for (size_t c = 0; c < corners.size(); ++c) {
            const uint32_t v = uint32_t(corners[c] >> 32), corner = uint32_t(corners[c]);
            if (mGlobal.empty() || mGlobal.back() != v) mGlobal.push_back(v);
            mTris[corner / 3][corner % 3] = uint32_t(mGlobal.size() - 1);
        }
        const size_t nv = mGlobal.size();
        mTriAlive.assign(n, 1);
        mStart.assign(nv + 1, 0);
        for (const Tri& t : mTris)
            for (uint32_t v : t)
                ++mStart[v + 1];
        for (size_t v = 0; v < nv; ++v)
            mStart[v + 1] += mStart[v];
        mCount.resize(nv);
        for (size_t v = 0; v < nv; ++v)
            mCount[v] = mStart[v + 1] - mStart[v];
        mRefs.resize(3 * n);
        std::vector<uint32_t> fill(mStart.begin(), mStart.end() - 1);
        for (size_t t = 0; t < n; ++t)
            for (uint32_t v : mTris[t])
                mRefs[fill[v]++] = uint32_t(t);
        mStart.pop_back();
        mOwn.resize(nv);
        for (size_t v = 0; v < nv; ++v)
            mOwn[v] = mCount[v] == valence[mGlobal[v]] && isClosedFan(uint32_t(v));
        mVersion.assign(nv, 0);
    }

    BlockResult run(double threshold, const DecimateTarget& target, size_t budget)
    {
        BlockResult out;
        mThreshold = threshold, mMaxDrift = target.maxDrift, mMaxStep = target.maxStep;
        std::vector<Entry> entries; // made a heap at once: cheaper than pushing one by one
        entries.reserve(3 * mTris.size() / 2);
        for (size_t t = 0; t < mTris.size(); ++t)
            for (int k = 0; k < 3; ++k) // each inner edge once, from its lower end
                if (mTris[t][k] < mTris[t][(k + 1) % 3])
                    push(mTris[t][k], mTris[t][(k + 1) % 3], &entries);
        mHeap = std::priority_queue<Entry>(std::less<Entry>(), std::move(entries));
        while (!mHeap.empty() && out.collapses < budget) {
            const Entry e = mHeap.top();
            mHeap.pop();
            if (mVersion[e.a] != e.versionA || mVersion[e.b] != e.versionB) continue; // stale
            if (collapse(e.a, e.b)) {
                ++out.collapses;
                out.maxError = std::max(out.maxError, e.error);
                out.maxDrift = std::max(out.maxDrift, double(mS.drift[mGlobal[e.a]]));
            } else {
                ++out.refused;
            }
        }
        for (size_t t = 0; t < mTris.size(); ++t)
            if (mTriAlive[t])
                out.triangles.push_back(
                    {mGlobal[mTris[t][0]], mGlobal[mTris[t][1]], mGlobal[mTris[t][2]]});
        return out;
    }

private:
    struct Entry
    {
        double error;
        uint32_t a, b, versionA, versionB;
        /// the heap's top is the smallest error, ties to the lowest ends: one order every run
        bool operator<(const Entry& o) const
        {
            return error != o.error ? error > o.error : a != o.a ? a > o.a : b > o.b;
        }
    };

    Vec3d& point(uint32_t v) { return mS.points[mGlobal[v]]; }

    void aliveTris(uint32_t v, std::vector<uint32_t>& out) const
    {
        out.clear();
        for (uint32_t i = mStart[v]; i < mStart[v] + mCount[v]; ++i)
            if (mTriAlive[mRefs[i]]) out.push_back(mRefs[i]);
    }

    void neighbours(const std::vector<uint32_t>& tris, uint32_t v, std::vector<uint32_t>& out)
    {
        out.clear();
        for (uint32_t t : tris)
            for (uint32_t w : mTris[t])
                if (w != v) out.push_back(w);
        std::sort(out.begin(), out.end());
        out.erase(std::unique(out.begin(), out.end()), out.end());
    }

    /// v's triangles go once around it, a disc: each triangle's far side leads to the next.
    bool isClosedFan(uint32_t v)
    {
        const uint32_t n = mCount[v];
        if (n < 3 || n > kMaxFan) return false;
        uint32_t from[kMaxFan], to[kMaxFan];
        for (uint32_t i = 0; i < n; ++i) {
            const Tri& t = mTris[mRefs[mStart[v] + i]];
            const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
            from[i] = t[(k + 1) % 3], to[i] = t[(k + 2) % 3];
        }
        uint32_t cur = from[0];
        uint64_t seen = 0;
        for (uint32_t step = 0; step < n; ++step) {
            uint32_t i = 0;
            while (i < n && from[i] != cur)
                ++i;
            if (i == n || (seen >> i & 1)) return false; // the fan is open, or not one fan
            seen |= uint64_t(1) << i;
            cur = to[i];
            if ((cur == from[0]) != (step == n - 1)) return false; // back too soon or never
        }
        return true;
    }

    void push(uint32_t a, uint32_t b, std::vector<Entry>* entries = nullptr)
    {
        if (!mOwn[a] || !mOwn[b]) return;
        if (a > b) std::swap(a, b);
        const Collapse c = bestCollapse(mS, mGlobal[a], mGlobal[b]);
        if (!(c.error <= mThreshold)) return;
        const Entry e{c.error, a, b, mVersion[a], mVersion[b]};
        entries ? entries->push_back(e) : mHeap.push(e);
    }

    bool collapse(uint32_t a, uint32_t b)
    {
        aliveTris(a, mTa);
        aliveTris(b, mTb);
        uint32_t shared[2], opposite[2], nShared = 0;
        for (uint32_t t : mTa) {
            const Tri& tri = mTris[t];
            if (tri[0] != b && tri[1] != b && tri[2] != b) continue;
            if (nShared == 2) return false; // a non-manifold edge
            shared[nShared] = t;
            opposite[nShared++] = tri[0] ^ tri[1] ^ tri[2] ^ a ^ b;
        }
        if (nShared != 2) return false;
        const Collapse col = bestCollapse(mS, mGlobal[a], mGlobal[b]);
        const bool stepBound = mMaxStep < std::numeric_limits<double>::infinity();
        double drift = 0; // see State::drift
        mAfter.clear(), mBefore.clear();
        size_t nGone = 0;
        for (const std::vector<uint32_t>* list : {&mTa, &mTb})
            for (uint32_t t : *list) {
                Vec3d before[3], after[3];
                double corners = 0; // the plane is as far off as its corners may be
                for (int k = 0; k < 3; ++k) {
                    const uint32_t v = mTris[t][k];
                    before[k] = point(v);
                    after[k] = v == a || v == b ? col.point : before[k];
                    corners = std::max(corners, double(mS.drift[mGlobal[v]]));
                }
                const Vec3d n0 = (before[1] - before[0]).cross(before[2] - before[0]);
                const double l0 = n0.length();
                if (l0 > 0)
                    drift = std::max(drift, std::abs(n0.dot(col.point - before[0])) / l0 + corners);
                const bool gone = t == shared[0] || t == shared[1];
                if (stepBound && !(gone && list == &mTb)) { // the two that go are in both fans
                    mBefore.push_back(
                        {before[0], before[1], before[2], after[0], after[1], after[2]});
                    if (gone) std::swap(mBefore.back(), mBefore[nGone++]); // first: see withinStep
                }
                if (gone) continue;
                mAfter.push_back({after[0], after[1], after[2]});
                const Vec3d n1 = (after[1] - after[0]).cross(after[2] - after[0]);
                const double l1 = n1.length();
                if (!(l1 > 0) || n0.dot(n1) < kMaxTurnCos * l0 * l1) return false;
                const double q1 = quality(after[0], after[1], after[2]);
                if (q1 < kMinQuality && q1 < quality(before[0], before[1], before[2])) return false;
            }
        // the topology, after the shapes: they refuse most collapses, and more cheaply
        neighbours(mTa, a, mNa);
        neighbours(mTb, b, mNb);
        size_t common = 0;
        for (size_t i = 0, j = 0; i < mNa.size() && j < mNb.size();)
            if (mNa[i] < mNb[j])
                ++i;
            else if (mNb[j] < mNa[i])
                ++j;
            else
                ++common, ++i, ++j;
        if (common != 2) return false;                     // the link condition
        if (mNa.size() + mNb.size() - 4 < 3) return false; // a's fan after the collapse
        for (uint32_t c : opposite) {                      // each loses one triangle
            aliveTris(c, mTc);
            if (mTc.size() - 1 < (mOwn[c] ? 3u : 2u)) return false;
        }
        if (drift > mMaxDrift) return false;
        if (stepBound && !withinStep(a, b, col.point)) return false;

        // commit: b merges into a
        point(a) = col.point;
        mS.drift[mGlobal[a]] = float(drift);
        mS.quadrics[mGlobal[a]] += mS.quadrics[mGlobal[b]];
        mTriAlive[shared[0]] = mTriAlive[shared[1]] = 0;
        const uint32_t start = uint32_t(mRefs.size());
        for (uint32_t t : mTa)
            if (t != shared[0] && t != shared[1]) mRefs.push_back(t);
        for (uint32_t t : mTb) {
            if (t == shared[0] || t == shared[1]) continue;
            for (uint32_t& v : mTris[t])
                if (v == b) v = a;
            mRefs.push_back(t);
        }
        mStart[a] = start, mCount[a] = uint32_t(mRefs.size()) - start;
        mCount[b] = 0;
        ++mVersion[a], ++mVersion[b], mOwn[b] = 0;
        aliveTris(a, mTa);
        neighbours(mTa, a, mNa);
        for (uint32_t w : mNa)
            push(a, w);
        return true;
    }

    /// DecimateTarget::maxStep: the new point p near an old triangle (one of the two the edge
    /// leaves, as a rule), and the old surface near the new: each old end, and each old
    /// triangle's middle (standing for the surface it covered) near a new triangle. mBefore
    /// holds the old fan (the two that go first), before and after the move.
    bool withinStep(uint32_t a, uint32_t b, const Vec3d& p)
    {
        const double bound = mMaxStep;
        bool nearOld = false;
        mFar.clear();
        for (uint32_t v : {a, b}) // an end that moves less than the bound is near all new
            if ((point(v) - p).length() <= bound)
                nearOld = true;
            else
                mFar.push_back(point(v));
        for (size_t i = 0; i < mBefore.size() && !nearOld; ++i)
            nearOld = withinDistance(p, mBefore[i][0], mBefore[i][1], mBefore[i][2], bound);
        if (!nearOld) return false;
        for (const auto& t : mBefore) {
            // near the same triangle moved, as a rule (its middle moved a third of its moving
            // corner's way); one of the two that go is a segment of the new fan
            const Vec3d middle = (t[0] + t[1] + t[2]) / 3.0;
            if (((t[3] + t[4] + t[5]) / 3.0 - middle).length() > bound &&
                !withinDistance(middle, t[3], t[4], t[5], bound))
                mFar.push_back(middle);
        }
        for (const Vec3d& q : mFar) {
            bool near = false;
            for (size_t i = 0; i < mAfter.size() && !near; ++i)
                near = withinDistance(q, mAfter[i][0], mAfter[i][1], mAfter[i][2], bound);
            if (!near) return false;
        }
        return true;
    }

    State& mS;
    std::vector<uint32_t> mGlobal; ///< local vertex -> mesh vertex, ascending
    std::vector<Tri> mTris;        ///< in local vertices
    std::vector<uint8_t> mTriAlive, mOwn;
    std::vector<uint32_t> mStart, mCount, mRefs; ///< vertex -> its triangles (lists grow at
                                                 ///< the end of mRefs as vertices merge)
    std::vector<uint32_t> mVersion;              ///< bumped when a vertex moves or goes
    std::priority_queue<Entry> mHeap;
    double mThreshold = 0, mMaxDrift = 0, mMaxStep = 0;
    std::vector<std::array<Vec3d, 3>> mAfter;      // the new fan
    std::vector<Vec3d> mFar;                       // old points to find near the new fan
    std::vector<std::array<Vec3d, 6>> mBefore;     // the old fan, before and after the move
    std::vector<uint32_t> mTa, mTb, mTc, mNa, mNb; // scratch
};

State makeState(const TriangleMesh& mesh)
{
    State s;
    Vec3d lo(std::numeric_limits<double>::max()), hi(-std::numeric_limits<double>::max());
    for (const Vec3f& p : mesh.points)
        for (int k = 0; k < 3; ++k)
            lo[k] = std::min(lo[k], double(p[k])), hi[k] = std::max(hi[k], double(p[k]));
    if (!mesh.points.empty()) s.middle = (lo + hi) * 0.5;
    s.points.resize(mesh.points.size());
    for (size_t v = 0; v < mesh.points.size(); ++v)
        s.points[v] = toVec3d(mesh.points[v]) - s.middle;
    s.triangles = mesh.triangles;
    s.drift.assign(mesh.points.size(), 0.f);
    // each vertex: the planes of its triangles, weighted by area (serial, in triangle order:
    // the same sums every run)
    s.quadrics.resize(mesh.points.size());
    for (const Tri& t : s.triangles) {
        const Vec3d n = (s.points[t[1]] - s.points[t[0]]).cross(s.points[t[2]] - s.points[t[0]]);
        const double len = n.length();
        if (!(len > 0)) continue;
        const Quadric q = Quadric::plane(n / len, s.points[t[0]], len / 2);
        for (uint32_t v : t)
            s.quadrics[v] += q;
    }
    return s;
}

/// Each triangle's block (the cube its centroid is in, cubes shifted by `shift` sides), as a
/// sort key: triangles sorted by it are grouped by block, in triangle order within each.
std::vector<uint64_t> blockOrder(const State& s, double side, double shift)
{
    const size_t n = s.triangles.size();
    std::vector<uint64_t> order(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t) {
            const Tri& tri = s.triangles[t];
            const Vec3d c = (s.points[tri[0]] + s.points[tri[1]] + s.points[tri[2]]) / 3.0;
            uint64_t key = 0;
            for (int k = 0; k < 3; ++k) // 10 bits an axis: 1,024 blocks across is plenty
                key =
                    key << 10 | (uint64_t(int64_t(std::floor(c[k] / side + shift)) + 512) & 1023u);
            order[t] = key << 32 | t;
        }
    });
    tbb::parallel_sort(order.begin(), order.end());
    return order;
}

} // namespace

TriangleMesh decimate(const TriangleMesh& mesh, const DecimateTarget& target, DecimateStats* stats,
                      std::vector<uint32_t>* kept)
{
    DecimateStats st;
    State s = makeState(mesh);
    size_t idle = 0;       // passes in a row without a collapse
    double rankFactor = 3; // collapses under the threshold per collapse made
    for (size_t pass = 0; pass < kMaxPasses; ++pass) {
        const size_t n = s.triangles.size();
        const bool countTarget = target.triangles > 0;
        const size_t needed = !countTarget           ? SIZE_MAX
                              : n > target.triangles ? (n - target.triangles + 1) / 2
                                                     : 0;
        if (needed == 0 || n == 0) break;

        // blocks: ~kBlockEdges mean edges across, so that their borders are a small part
        double edgeSum = 0;
        for (const Tri& t : s.triangles)
            edgeSum += (s.points[t[1]] - s.points[t[0]]).length();
        double side = kBlockEdges * std::max(edgeSum / double(n), 1e-30);
        Vec3d lo(std::numeric_limits<double>::max()), hi(-lo[0]);
        for (const Vec3d& p : s.points)
            for (int k = 0; k < 3; ++k)
                lo[k] = std::min(lo[k], p[k]), hi[k] = std::max(hi[k], p[k]);
        for (int k = 0; k < 3; ++k) // the points are centred: 1,000 blocks across at most
            side = std::max(side, 2.02 * std::max(std::abs(lo[k]), std::abs(hi[k])) / 1000);
        const std::vector<uint64_t> order = blockOrder(s, side, pass % 2 ? 0.5 : 0.0);
        std::vector<size_t> blockStart;
        for (size_t i = 0; i < n; ++i)
            if (i == 0 || order[i] >> 32 != order[i - 1] >> 32) blockStart.push_back(i);
        const size_t nb = blockStart.size();
        blockStart.push_back(n);
        std::vector<uint32_t> tris(n);
        for (size_t i = 0; i < n; ++i)
            tris[i] = uint32_t(order[i]);
        std::vector<uint32_t> valence(s.points.size(), 0);
        for (const Tri& t : s.triangles)
            for (uint32_t v : t)
                ++valence[v];

        // the pass' threshold, and each block's share of the collapses still needed, from the
        // edges of every kSample-th triangle (a quarter of the work for the same quantiles)
        std::vector<float> errors(3 * n, std::numeric_limits<float>::infinity());
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, n), [&](const tbb::blocked_range<size_t>& r) {
                for (size_t i = r.begin(); i != r.end(); ++i)
                    for (int k = 0; k < 3 && i % kSample == 0; ++k) {
                        const Tri& t = s.triangles[tris[i]];
                        if (t[k] < t[(k + 1) % 3])
                            errors[3 * i + k] = float(bestCollapse(s, t[k], t[(k + 1) % 3]).error);
                    }
            });
        double threshold = target.maxError;
        bool allEdges = true;
        // The last few collapses (under 1/kLastShare of the triangles) go to the blocks by
        // their size, cheapest first in each, with no threshold: when a threshold is left to
        // find them, each pass over the whole mesh makes only a handful.
        const bool last = countTarget && needed * kLastShare < n;
        if (countTarget && !last) {
            std::vector<float> sorted;
            sorted.reserve(3 * n / 2);
            for (float e : errors)
                if (e <= target.maxError && std::isfinite(e)) sorted.push_back(e);
            const double rank = rankFactor * double(needed) / kSample;
            if (rank < double(sorted.size())) {
                std::nth_element(sorted.begin(), sorted.begin() + size_t(rank), sorted.end());
                threshold = std::min(threshold, double(sorted[size_t(rank)]));
                allEdges = false;
            }
        }
        std::vector<size_t> budget(nb, SIZE_MAX);
        if (countTarget) {
            std::vector<size_t> under(nb, 0);
            size_t total = 0;
            for (size_t b = 0; b < nb; ++b) {
                if (last)
                    under[b] = blockStart[b + 1] - blockStart[b];
                else
                    for (size_t i = 3 * blockStart[b]; i < 3 * blockStart[b + 1]; ++i)
                        under[b] += errors[i] <= threshold;
                total += under[b];
            }
            size_t given = 0;
            for (size_t b = 0; b < nb; ++b)
                given += budget[b] = total ? size_t(double(needed) * double(under[b]) / total) : 0;
            for (size_t b = 0; b < nb && given < needed; ++b) // what rounding down left
                if (under[b] > 0) ++budget[b], ++given;
        }
        errors = {};

        std::vector<BlockResult> results(nb);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, nb, 1),
                          [&](const tbb::blocked_range<size_t>& r) {
                              for (size_t b = r.begin(); b != r.end(); ++b) {
                                  if (budget[b] == 0) {
                                      for (size_t i = blockStart[b]; i < blockStart[b + 1]; ++i)
                                          results[b].triangles.push_back(s.triangles[tris[i]]);
                                      continue;
                                  }
                                  Block block(s, &tris[blockStart[b]],
                                              blockStart[b + 1] - blockStart[b], valence);
                                  results[b] = block.run(threshold, target, budget[b]);
                              }
                          });
        size_t collapses = 0;
        s.triangles.clear();
        for (BlockResult& r : results) {
            collapses += r.collapses;
            st.refused += r.refused;
            st.maxError = std::max(st.maxError, r.maxError);
            st.maxDrift = std::max(st.maxDrift, r.maxDrift);
            s.triangles.insert(s.triangles.end(), r.triangles.begin(), r.triangles.end());
        }
        st.collapses += collapses;
        st.passes = pass + 1;
        if (!countTarget) {
            // everything under the bound was tried: once with each block offset is enough
            // unless a pass still finds work
            if (pass >= 1 && collapses <= n / 1000) break;
        } else if (allEdges) {
            idle = collapses ? 0 : idle + 1;
            if (idle == 2) break; // nothing left that the guards allow, with either offset
        } else if (4 * collapses < needed) {
            rankFactor *= 2; // collapses are refused or blocked more than expected
        }
    }

    // the result: used points in their old order
    TriangleMesh out;
    std::vector<uint32_t> index(s.points.size(), UINT32_MAX);
    if (kept) kept->clear();
    for (const Tri& t : s.triangles)
        for (uint32_t v : t)
            index[v] = 0;
    for (size_t v = 0; v < s.points.size(); ++v)
        if (index[v] == 0) {
            index[v] = uint32_t(out.points.size());
            out.points.push_back(toVec3f(s.points[v] + s.middle));
            if (kept) kept->push_back(uint32_t(v));
        }
    out.triangles.reserve(s.triangles.size());
    for (const Tri& t : s.triangles)
        out.triangles.push_back({index[t[0]], index[t[1]], index[t[2]]});
    computeAngleWeightedNormals(out);
    if (stats) *stats = st;
    return out;
}

} // namespace post
} // namespace fluidsurf
