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
//   ones (under a fifth of the triangles left) go to the blocks by their edges not remembered
//   as refused (see below), cheapest first in each.
// - Why not one serial heap (the textbook greedy): measured on the real frames, it pulled thin
//   tips in by 2-4 voxels whatever the weights or placement, where the passes keep them.
//
// Each collapse moves the edge to the point of least quadric error (not to one of its ends, as
// OpenMesh does): the error is measured against the original triangles' planes, which averages
// out the particles' bumps on flat fluid. Guards refuse a collapse that would
// - break manifoldness: the ends must share exactly the two neighbours across the edge (the
//   link condition), and no vertex may be left with fewer than three triangles;
// - turn a remaining triangle's normal by more than kMaxTurnDegrees (a fold or flip);
// - leave a triangle with an angle under kThinAngleDegrees (MeshCheck.h: what checkMesh counts
//   as thin) that was not already thinner (slivers);
// - carry a vertex farther from the input than DecimateTarget::maxDrift (see State::drift);
// - move the surface by more than DecimateTarget::maxStep, either way (post/StepGuard: the new
//   point, the old ends and triangle middles, and the new edges' middles).
// The shape guards run first: they refuse nine collapses in ten of those refused, and cheaply.
//
// A refusal is remembered across passes (State::refused): the guards read only the two ends'
// fans, so an edge refused once is refused again until a collapse changes a fan it reads (a
// collapse's vertex and its neighbours are "touched"). Near a count target the cheapest edges
// left are mostly refused ones; without the memory, every late pass tried them all again (15
// passes of 0.03-0.3 s for 9,000 collapses on the t0.50 1.69M frame). A remembered edge is
// left out of its block's heap and put in only when a collapse touches an end while the heap
// still holds the edge in pop order (Block::touch): the collapses made are the same, in the
// same order, as with every edge in the heap.
//
// Set-up costs count on two cores: a block numbers its vertices in the order they first appear
// (a per-thread table, not a sort), the blocks are found by a radix sort, and the quadrics are
// gathered per vertex in parallel.
#include "post/Decimate.h"

#include "post/Normals.h"
#include "post/Quadric.h"
#include "post/StepGuard.h"

#include "util/RadixSort.h"
#include "util/TriangleDistance.h"

#include <fluidsurf/MeshCheck.h>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <memory>
#include <queue>
#include <utility>

namespace fluidsurf {
namespace post {

namespace {

using Tri = std::array<uint32_t, 3>;

constexpr double kBlockEdges = 32;     ///< a block's side in mean edge lengths (~2,500 triangles)
constexpr double kMaxTurnDegrees = 60; ///< the most a remaining triangle's normal may turn
constexpr size_t kMaxPasses = 64;
constexpr size_t kLastShare = 5; ///< see "last" in decimate()
constexpr size_t kSample = 4;    ///< a pass' threshold from every kSample-th triangle's edges
constexpr size_t kMaxFan = 64;   ///< vertices with more triangles are left alone
constexpr uint32_t kNone = UINT32_MAX;

const double kMaxTurnCos = std::cos(kMaxTurnDegrees * M_PI / 180);
const double kMaxTurnCos2 = kMaxTurnCos * kMaxTurnCos; ///< the turn guard compares squares
/// sin^2 of the smallest angle the thin guard lets a new triangle have: a triangle's smallest
/// angle (<= 60 deg) has sin^2 = |n|^2 shortest^2 / (a^2 b^2 c^2), |n| twice its area.
const double kThinSin2 = std::pow(std::sin(kThinAngleDegrees * M_PI / 180), 2);

/// The whole mesh between passes, points relative to the middle of its bounds so that the
/// quadrics' constants stay small and their errors exact to many digits.
struct State
{
    Vec3d middle{0.0}; ///< of the input's bounds
    std::vector<Vec3d> points;
    std::unique_ptr<Quadric[]> quadrics; ///< one a point (see makeState)
    /// How far each vertex may be from the input surface it stands for: 0 for an input vertex;
    /// a collapse adds its point's largest distance to the planes of the triangles it replaces
    /// to the larger drift of its two ends (an upper bound along the normals, where the
    /// quadric's mean can hide a tip pulled in by a few voxels).
    std::vector<float> drift;
    std::vector<Tri> triangles;
    /// Per triangle, bit k: its edge (t[k], t[k + 1]) was refused, and no collapse has touched
    /// either end since (see the top of the file).
    std::vector<uint8_t> refused;
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

struct BlockResult
{
    std::vector<Tri> triangles;      ///< what is left of the block's triangles
    std::vector<uint8_t> remembered; ///< theirs (State::refused)
    /// Vertices the block does not own that its collapses touched: their remembered refusals
    /// in other blocks are forgotten after the pass.
    std::vector<uint32_t> touched;
    size_t collapses = 0, refused = 0;
    double maxError = 0, maxDrift = 0;
};

/// One block's greedy collapses (see the top of the file). Reads the points and quadrics of
/// every vertex of its triangles, writes only those of the vertices it owns.
class Block
{
public:
    /// `localOf`: one per thread, as long as the mesh's points, all kNone, and left so.
    Block(State& s, const uint32_t* tris, size_t n, const std::vector<uint32_t>& valence,
          std::vector<uint32_t>& localOf)
        : mS(s)
    {
        // local vertices in the order they first appear in the block's triangles (which are in
        // mesh order): the same numbering every run, without a sort
        mTris.resize(n);
        mRefused.resize(n);
        for (size_t i = 0; i < n; ++i) {
            mRefused[i] = s.refused[tris[i]];
            for (int k = 0; k < 3; ++k) {
                const uint32_t v = s.triangles[tris[i]][k];
                if (localOf[v] == kNone) {
                    localOf[v] = uint32_t(mGlobal.size());
                    mGlobal.push_back(v);
                }
                mTris[i][k] = localOf[v];
            }
        }
        for (uint32_t v : mGlobal)
            localOf[v] = kNone;
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
        mMark.assign(nv, 0);
    }

    BlockResult run(double threshold, const DecimateTarget& target, size_t budget)
    {
        BlockResult out;
        mThreshold = threshold, mMaxDrift = target.maxDrift, mMaxStep = target.maxStep;
        mStep = StepGuard(mMaxStep);
        std::vector<Entry> entries; // made a heap at once: cheaper than pushing one by one
        entries.reserve(3 * mTris.size() / 2);
        for (size_t t = 0; t < mTris.size(); ++t)
            for (int k = 0; k < 3; ++k) // each inner edge once, from its lower end
                if (mTris[t][k] < mTris[t][(k + 1) % 3] && !(mRefused[t] >> k & 1))
                    push(mTris[t][k], mTris[t][(k + 1) % 3], &entries);
        mHeap = std::priority_queue<Entry>(std::less<Entry>(), std::move(entries));
        mPopped = false;
        while (!mHeap.empty() && out.collapses < budget) {
            const Entry e = mHeap.top();
            mHeap.pop();
            if (popsAfterLast(e)) mLast = e, mPopped = true;
            const uint32_t a = uint32_t(e.key);
            if (mVersion[a] + mVersion[e.b] != e.versions) continue; // stale: an end changed
            double error = 0;
            const Outcome o = collapse(a, e.b, error);
            if (o == Outcome::Collapsed) {
                ++out.collapses;
                out.maxError = std::max(out.maxError, error);
                out.maxDrift = std::max(out.maxDrift, double(mS.drift[mGlobal[a]]));
                for (uint32_t w : mRing) // after collapse(): touch() walks with mMark too
                    touch(w, a, out.touched);
            } else {
                ++out.refused;
            }
        }
        for (size_t t = 0; t < mTris.size(); ++t)
            if (mTriAlive[t]) {
                out.triangles.push_back(
                    {mGlobal[mTris[t][0]], mGlobal[mTris[t][1]], mGlobal[mTris[t][2]]});
                out.remembered.push_back(mRefused[t]);
            }
        return out;
    }

private:
    /// 16 bytes, one integer compare as a rule: the heap's sifting is a tenth of the work.
    struct Entry
    {
        /// the error as a float (its bits order like the value: it is >= 0), then the lower
        /// end: the heap's top is the smallest error, ties to the lowest ends, one order every run
        uint64_t key;
        uint32_t b;
        uint32_t versions; ///< the ends' versions added up when pushed: they only grow
        bool operator<(const Entry& o) const { return key != o.key ? key > o.key : b > o.b; }
    };

    enum class Outcome {
        Collapsed,
        Refused,         ///< by the ends' fans alone: remembered (State::refused)
        RefusedUnstable, ///< by what lies outside the fans too: tried again next time
    };

    Vec3d& point(uint32_t v) { return mS.points[mGlobal[v]]; }
    const Vec3d& point(uint32_t v) const { return mS.points[mGlobal[v]]; }

    void aliveTris(uint32_t v, std::vector<uint32_t>& out) const
    {
        out.clear();
        for (uint32_t i = mStart[v]; i < mStart[v] + mCount[v]; ++i)
            if (mTriAlive[mRefs[i]]) out.push_back(mRefs[i]);
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

    /// The heap entry of edge (a, b), if it belongs in the heap.
    bool entry(uint32_t a, uint32_t b, Entry& e) const
    {
        if (!mOwn[a] || !mOwn[b]) return false;
        if (a > b) std::swap(a, b);
        const Collapse c = bestCollapse(mS, mGlobal[a], mGlobal[b]);
        if (!(c.error <= mThreshold)) return false;
        const float error = float(c.error);
        uint32_t bits;
        std::memcpy(&bits, &error, sizeof bits);
        e = Entry{uint64_t(bits) << 32 | a, b, mVersion[a] + mVersion[b]};
        return true;
    }

    void push(uint32_t a, uint32_t b, std::vector<Entry>* entries = nullptr)
    {
        Entry e;
        if (entry(a, b, e)) entries ? entries->push_back(e) : mHeap.push(e);
    }

    /// e comes after every entry popped so far (the heap's order: the top is the largest).
    bool popsAfterLast(const Entry& e) const { return !mPopped || e < mLast; }

    /// Remembers the refusal of edge (a, b) on both its triangles.
    Outcome refuse(uint32_t a, uint32_t b, const uint32_t (&shared)[2])
    {
        for (uint32_t t : shared)
            for (int k = 0; k < 3; ++k) {
                const uint32_t p = mTris[t][k], q = mTris[t][(k + 1) % 3];
                if ((p == a && q == b) || (p == b && q == a)) mRefused[t] |= uint8_t(1 << k);
            }
        return Outcome::Refused;
    }

    /// A collapse into `a` changed u's fan: u's remembered refusals no longer hold. Those the
    /// heap would still hold, had they been in it (after the last entry popped), go in now; the
    /// edges to `a` are in already. `touched` gets u if the block does not own it.
    void touch(uint32_t u, uint32_t a, std::vector<uint32_t>& touched)
    {
        if (!mOwn[u]) {
            touched.push_back(mGlobal[u]);
            return;
        }
        const uint32_t stamp = ++mStamp;
        for (uint32_t i = mStart[u]; i < mStart[u] + mCount[u]; ++i) {
            const uint32_t t = mRefs[i];
            if (!mTriAlive[t] || !mRefused[t]) continue;
            for (int k = 0; k < 3; ++k) {
                const uint32_t p = mTris[t][k], q = mTris[t][(k + 1) % 3];
                if (!(mRefused[t] >> k & 1) || (p != u && q != u)) continue;
                mRefused[t] &= uint8_t(~(1 << k));
                const uint32_t v = p == u ? q : p;
                if (v == a || mMark[v] == stamp) continue;
                mMark[v] = stamp;
                Entry e;
                if (entry(u, v, e) && popsAfterLast(e)) mHeap.push(e);
            }
        }
    }

    Outcome collapse(uint32_t a, uint32_t b, double& error)
    {
        aliveTris(a, mTa);
        aliveTris(b, mTb);
        uint32_t shared[2], opposite[2], nShared = 0;
        for (uint32_t t : mTa) {
            const Tri& tri = mTris[t];
            if (tri[0] != b && tri[1] != b && tri[2] != b) continue;
            if (nShared == 2) return Outcome::RefusedUnstable; // a non-manifold edge
            shared[nShared] = t;
            opposite[nShared++] = tri[0] ^ tri[1] ^ tri[2] ^ a ^ b;
        }
        if (nShared != 2) return Outcome::RefusedUnstable;
        const Collapse col = bestCollapse(mS, mGlobal[a], mGlobal[b]);
        // the shapes first: they refuse most collapses (nine in ten refused), and cheaply: in
        // squares, without roots. Each remaining triangle of v's fan is (v, u, w) in its own
        // order, with only v moving, from x to the new point q.
        const Vec3d& q = col.point;
        for (const uint32_t v : {a, b}) {
            const Vec3d x = point(v);
            for (uint32_t t : v == a ? mTa : mTb) {
                if (t == shared[0] || t == shared[1]) continue;
                const Tri& tri = mTris[t];
                const int k = tri[0] == v ? 0 : tri[1] == v ? 1 : 2;
                const Vec3d& u = point(tri[(k + 1) % 3]);
                const Vec3d& w = point(tri[(k + 2) % 3]);
                const Vec3d n0 = (u - x).cross(w - x), n1 = (u - q).cross(w - q);
                const double turn = n0.dot(n1), l0 = n0.lengthSqr(), l1 = n1.lengthSqr();
                if (!(l1 > 0) || turn < 0 || turn * turn < kMaxTurnCos2 * l0 * l1)
                    return refuse(a, b, shared);
                // an angle under kThinAngleDegrees, smaller than it was (see kThinSin2)
                const double uw = (u - w).lengthSqr(), uq = (u - q).lengthSqr(),
                             wq = (w - q).lengthSqr();
                const double sides1 = uw * uq * wq, short1 = std::min({uw, uq, wq});
                if (l1 * short1 < kThinSin2 * sides1) {
                    const double ux = (u - x).lengthSqr(), wx = (w - x).lengthSqr();
                    const double sides0 = uw * ux * wx, short0 = std::min({uw, ux, wx});
                    if (l1 * short1 * sides0 < l0 * short0 * sides1) return refuse(a, b, shared);
                }
            }
        }
        // the topology: the ends' neighbours, marked with stamps (no sorting)
        const uint32_t markA = ++mStamp, markB = ++mStamp;
        size_t na = 0, nb = 0, common = 0; // b is a's neighbour and a b's
        for (uint32_t t : mTa)
            for (uint32_t w : mTris[t])
                if (w != a && mMark[w] != markA) mMark[w] = markA, ++na;
        for (uint32_t t : mTb)
            for (uint32_t w : mTris[t]) {
                if (w == b || mMark[w] == markB) continue;
                common += mMark[w] == markA;
                mMark[w] = markB, ++nb;
            }
        if (common != 2) return refuse(a, b, shared);     // the link condition
        if (na + nb - 4 < 3) return refuse(a, b, shared); // a's fan after the collapse
        for (uint32_t c : opposite) { // each loses one triangle (c's fan: not remembered)
            aliveTris(c, mTc);
            if (mTc.size() - 1 < (mOwn[c] ? 3u : 2u)) return Outcome::RefusedUnstable;
        }
        // how far the surface moves: the drift bound, and the fans for withinStep
        const bool stepBound = mMaxStep < std::numeric_limits<double>::infinity();
        double drift = 0; // see State::drift
        // (a plane of the old fan is as far off the input as its corners may be)
        auto far = [&](const Tri& t) {
            return double(std::max(
                {mS.drift[mGlobal[t[0]]], mS.drift[mGlobal[t[1]]], mS.drift[mGlobal[t[2]]]}));
        };
        auto driftTo = [&](const Vec3d& x, const Vec3d& u, const Vec3d& w, const Tri& t) {
            const Vec3d n0 = (u - x).cross(w - x);
            const double l0 = n0.length();
            if (l0 > 0) drift = std::max(drift, std::abs(n0.dot(q - x)) / l0 + far(t));
        };
        mStep.start(q);
        // the two that go, first (see StepGuard): each a segment from q to its far corner now
        for (int g = 0; g < 2; ++g) {
            const Tri& tri = mTris[shared[g]];
            const Vec3d &x = point(tri[0]), &u = point(tri[1]), &w = point(tri[2]);
            driftTo(x, u, w, tri);
            if (stepBound) mStep.addGone(tri, x, u, w, opposite[g], point(opposite[g]));
        }
        // the others, (v, u, w) with only v moving from x to q
        for (const uint32_t v : {a, b}) {
            if (v == b) mStep.startSecondFan();
            const Vec3d x = point(v);
            for (uint32_t t : v == a ? mTa : mTb) {
                if (t == shared[0] || t == shared[1]) continue;
                const Tri& tri = mTris[t];
                const int k = tri[0] == v ? 0 : tri[1] == v ? 1 : 2;
                const Tri ids{v, tri[(k + 1) % 3], tri[(k + 2) % 3]};
                const Vec3d &u = point(ids[1]), &w = point(ids[2]);
                driftTo(x, u, w, tri);
                if (stepBound) mStep.addMoved(ids, x, u, w);
            }
        }
        if (drift > mMaxDrift) return refuse(a, b, shared);
        if (stepBound && !mStep.accepts(point(a), point(b))) return refuse(a, b, shared);
        error = col.error;

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
        const uint32_t mark = ++mStamp;
        mRing.clear();
        for (uint32_t t : mTa) {
            for (uint32_t w : mTris[t])
                if (w != a && mMark[w] != mark) mMark[w] = mark, mRing.push_back(w), push(a, w);
            for (int k = 0; k < 3; ++k) // a's own edges are all in the heap again
                if (mTris[t][k] == a || mTris[t][(k + 1) % 3] == a)
                    mRefused[t] &= uint8_t(~(1 << k));
        }
        return Outcome::Collapsed;
    }

    State& mS;
    std::vector<uint32_t> mGlobal; ///< local vertex -> mesh vertex
    std::vector<Tri> mTris;        ///< in local vertices
    std::vector<uint8_t> mTriAlive, mOwn;
    std::vector<uint8_t> mRefused;               ///< State::refused, per local triangle
    std::vector<uint32_t> mStart, mCount, mRefs; ///< vertex -> its triangles (lists grow at
                                                 ///< the end of mRefs as vertices merge)
    std::vector<uint32_t> mVersion;              ///< bumped when a vertex moves or goes
    std::priority_queue<Entry> mHeap;
    double mThreshold = 0, mMaxDrift = 0, mMaxStep = 0;
    StepGuard mStep{0};          ///< the fans of the collapse being tried (DecimateTarget::maxStep)
    std::vector<uint32_t> mMark; ///< per vertex: the stamp of the last neighbour walk it was in
    uint32_t mStamp = 0;
    std::vector<uint32_t> mTa, mTb, mTc; // scratch
    std::vector<uint32_t> mRing;         ///< the last collapse's vertex' neighbours
    Entry mLast{};                       ///< the last entry popped in heap order (see touch)
    bool mPopped = false;
};

/// mesh's triangles move into the state (a copy of 23 MB on the 1.7M-particle frames).
State makeState(TriangleMesh& mesh)
{
    State s;
    const size_t nv = mesh.points.size();
    using Bounds = std::pair<Vec3d, Vec3d>; // min and max: exact in any order
    const double big = std::numeric_limits<double>::max();
    const Bounds bounds = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, nv), Bounds(Vec3d(big), Vec3d(-big)),
        [&](const tbb::blocked_range<size_t>& r, Bounds b) {
            for (size_t v = r.begin(); v != r.end(); ++v)
                for (int k = 0; k < 3; ++k)
                    b.first[k] = std::min(b.first[k], double(mesh.points[v][k])),
                    b.second[k] = std::max(b.second[k], double(mesh.points[v][k]));
            return b;
        },
        [](Bounds a, const Bounds& b) {
            for (int k = 0; k < 3; ++k)
                a.first[k] = std::min(a.first[k], b.first[k]),
                a.second[k] = std::max(a.second[k], b.second[k]);
            return a;
        });
    if (nv > 0) s.middle = (bounds.first + bounds.second) * 0.5;
    s.points.resize(nv);
    // not zeroed: filled below in parallel, where its pages are first touched
    s.quadrics.reset(new Quadric[nv]);
    // each vertex gathers the planes of its triangles, weighted by area, in triangle order: the
    // same sums every run
    const VertexTriangles around(mesh);
    s.triangles = std::move(mesh.triangles);
    mesh.normals = {}; // not used here (the result gets new ones): 12 bytes a vertex back
    s.refused.assign(s.triangles.size(), 0);
    s.drift.assign(nv, 0.f);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v)
            s.points[v] = toVec3d(mesh.points[v]) - s.middle;
    });
    mesh.points = {}; // s.points has them
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v) {
            Quadric q{};
            for (uint32_t i = around.start[v]; i < around.start[v + 1]; ++i) {
                const Tri& t = s.triangles[around.tris[i]];
                const Vec3d n = sideCross(s.points, t);
                const double len = n.length();
                if (len > 0) q += Quadric::plane(n / len, s.points[t[0]], len / 2);
            }
            s.quadrics[v] = q;
        }
    });
    return s;
}

/// The triangles grouped by block (the cube of side `side` its centroid is in, cubes shifted by
/// `shift` sides), in triangle order within each: tris[start[b], start[b + 1]) are block b's.
struct Blocks
{
    std::vector<uint32_t> tris;
    std::vector<size_t> start;
};

Blocks sortIntoBlocks(const State& s, double side, double shift)
{
    const size_t n = s.triangles.size();
    std::vector<uint64_t> keys(n);       // (block, triangle)
    constexpr int kBits = 10, kAxes = 3; // 10 bits an axis: 1,024 blocks across is plenty
    constexpr uint32_t kMask = (1u << kBits) - 1;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t) {
            const Tri& tri = s.triangles[t];
            const Vec3d c = (s.points[tri[0]] + s.points[tri[1]] + s.points[tri[2]]) / 3.0;
            uint64_t key = 0;
            for (int k = 0; k < kAxes; ++k)
                key = key << kBits |
                      (uint64_t(int64_t(std::floor(c[k] / side + shift)) + 512) & kMask);
            keys[t] = key << 32 | t;
        }
    });
    // by block, stably: the triangles are already in order, so this is the sort by (block,
    // triangle)
    util::radixSortStable(keys, kBits * kAxes, [](uint64_t k) { return k >> 32; });
    Blocks b;
    b.tris.resize(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i)
            b.tris[i] = uint32_t(keys[i]);
    });
    for (size_t i = 0; i < n; ++i)
        if (i == 0 || keys[i] >> 32 != keys[i - 1] >> 32) b.start.push_back(i);
    b.start.push_back(n);
    return b;
}

/// The side of a pass' blocks: ~kBlockEdges mean edges across, so that their borders are a
/// small part; 1,000 blocks across at most.
double blockSide(const State& s)
{
    const size_t n = s.triangles.size();
    // (a deterministic reduction: fixed chunks added in a fixed tree, for any thread count)
    const double edgeSum = tbb::parallel_deterministic_reduce(
        tbb::blocked_range<size_t>(0, n, 4096), 0.0,
        [&](const tbb::blocked_range<size_t>& r, double sum) {
            for (size_t t = r.begin(); t != r.end(); ++t)
                sum += (s.points[s.triangles[t][1]] - s.points[s.triangles[t][0]]).length();
            return sum;
        },
        std::plus<double>());
    const double reach = tbb::parallel_reduce( // the points are centred: max |coordinate|
        tbb::blocked_range<size_t>(0, s.points.size()), 0.0,
        [&](const tbb::blocked_range<size_t>& r, double m) {
            for (size_t v = r.begin(); v != r.end(); ++v)
                for (int k = 0; k < 3; ++k)
                    m = std::max(m, std::abs(s.points[v][k]));
            return m;
        },
        [](double a, double b) { return std::max(a, b); });
    return std::max(kBlockEdges * std::max(edgeSum / double(std::max<size_t>(n, 1)), 1e-30),
                    2.02 * reach / 1000);
}

/// A pass' threshold and each block's share of the collapses still needed.
struct Shares
{
    double threshold;
    bool allEdges;              ///< no threshold was drawn: every edge under the bound is in play
    std::vector<size_t> budget; ///< collapses per block
};

/// The threshold from the edges of every kSample-th triangle (a quarter of the work for the
/// same quantiles): the rankFactor * needed cheapest collapses lie under it; each block's share
/// in proportion to its sampled edges under it, or (`last`) to its edges not remembered as
/// refused.
Shares shareOut(const State& s, const Blocks& blocks, double maxError, size_t needed, bool last,
                double rankFactor)
{
    const size_t n = s.triangles.size(), nb = blocks.start.size() - 1;
    const std::vector<uint32_t>& tris = blocks.tris;
    const std::vector<size_t>& blockStart = blocks.start;
    Shares sh{maxError, true, std::vector<size_t>(nb, 0)};
    std::vector<float> errors; // by block order; infinite where not sampled
    if (!last) {
        errors.assign(3 * n, std::numeric_limits<float>::infinity());
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, n), [&](const tbb::blocked_range<size_t>& r) {
                for (size_t i = r.begin(); i != r.end(); ++i)
                    for (int k = 0; k < 3 && i % kSample == 0; ++k) {
                        const Tri& t = s.triangles[tris[i]];
                        if (t[k] < t[(k + 1) % 3])
                            errors[3 * i + k] = float(bestCollapse(s, t[k], t[(k + 1) % 3]).error);
                    }
            });
        std::vector<float> sorted;
        sorted.reserve(3 * n / 2 / kSample);
        for (float e : errors)
            if (e <= maxError && std::isfinite(e)) sorted.push_back(e);
        const double rank = rankFactor * double(needed) / kSample;
        if (rank < double(sorted.size())) {
            std::nth_element(sorted.begin(), sorted.begin() + size_t(rank), sorted.end());
            sh.threshold = std::min(sh.threshold, double(sorted[size_t(rank)]));
            sh.allEdges = false;
        }
    }
    std::vector<size_t> under(nb, 0);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nb), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t b = r.begin(); b != r.end(); ++b)
            if (last) // the block's edges not remembered as refused (each counted twice)
                for (size_t i = blockStart[b]; i < blockStart[b + 1]; ++i)
                    under[b] += size_t(__builtin_popcount(~s.refused[tris[i]] & 7u));
            else
                for (size_t i = 3 * blockStart[b]; i < 3 * blockStart[b + 1]; ++i)
                    under[b] += errors[i] <= sh.threshold;
    });
    size_t total = 0;
    for (size_t u : under)
        total += u;
    size_t given = 0;
    for (size_t b = 0; b < nb; ++b)
        given += sh.budget[b] = total ? size_t(double(needed) * double(under[b]) / total) : 0;
    for (size_t b = 0; b < nb && given < needed; ++b) // what rounding down left
        if (under[b] > 0) ++sh.budget[b], ++given;
    return sh;
}

/// Forgets the refusals (State::refused) of the edges with a touched end, and clears `touched`.
void forgetTouched(State& s, std::vector<uint8_t>& touched)
{
    tbb::parallel_for(tbb::blocked_range<size_t>(0, s.triangles.size()),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t t = r.begin(); t != r.end(); ++t) {
                              if (!s.refused[t]) continue;
                              const Tri& tri = s.triangles[t];
                              for (int k = 0; k < 3; ++k)
                                  if (touched[tri[k]] || touched[tri[(k + 1) % 3]])
                                      s.refused[t] &= uint8_t(~(1 << k));
                          }
                      });
    std::fill(touched.begin(), touched.end(), uint8_t(0));
}

/// The state's mesh: the points its triangles use, in their old order (`kept`, if given: their
/// indices in the input).
TriangleMesh compact(const State& s, std::vector<uint32_t>* kept)
{
    TriangleMesh out;
    std::vector<uint32_t> index(s.points.size(), UINT32_MAX);
    if (kept) kept->clear();
    const size_t nt = s.triangles.size();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nt), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t)
            for (uint32_t v : s.triangles[t]) // a mark: any order, any repeat
                __atomic_store_n(&index[v], 0u, __ATOMIC_RELAXED);
    });
    for (size_t v = 0; v < s.points.size(); ++v)
        if (index[v] == 0) {
            index[v] = uint32_t(out.points.size());
            out.points.push_back(toVec3f(s.points[v] + s.middle));
            if (kept) kept->push_back(uint32_t(v));
        }
    out.triangles.resize(nt);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nt), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t) {
            const Tri& tri = s.triangles[t];
            out.triangles[t] = {index[tri[0]], index[tri[1]], index[tri[2]]};
        }
    });
    return out;
}

} // namespace

TriangleMesh decimate(TriangleMesh mesh, const DecimateTarget& target, DecimateStats* stats,
                      std::vector<uint32_t>* kept)
{
    DecimateStats st;
    State s = makeState(mesh);
    size_t idle = 0;               // passes in a row without a collapse
    double rankFactor = 3;         // collapses under the threshold per collapse made
    std::vector<uint32_t> valence; // each point's triangles
    std::vector<uint8_t> touched(s.points.size(), 0); // see BlockResult::touched
    tbb::enumerable_thread_specific<std::vector<uint32_t>> localOf(
        std::vector<uint32_t>(s.points.size(), kNone)); // see Block
    for (size_t pass = 0; pass < kMaxPasses; ++pass) {
        const size_t n = s.triangles.size();
        const bool countTarget = target.triangles > 0;
        const size_t needed = !countTarget           ? SIZE_MAX
                              : n > target.triangles ? (n - target.triangles + 1) / 2
                                                     : 0;
        if (needed == 0 || n == 0) break;

        const Blocks blocks = sortIntoBlocks(s, blockSide(s), pass % 2 ? 0.5 : 0.0);
        const std::vector<uint32_t>& tris = blocks.tris;
        const std::vector<size_t>& blockStart = blocks.start;
        const size_t nb = blockStart.size() - 1;
        valence.assign(s.points.size(), 0);
        tbb::parallel_for(tbb::blocked_range<size_t>(0, n),
                          [&](const tbb::blocked_range<size_t>& r) {
                              for (size_t t = r.begin(); t != r.end(); ++t)
                                  for (uint32_t v : s.triangles[t]) // counts: the same in any order
                                      __atomic_fetch_add(&valence[v], 1u, __ATOMIC_RELAXED);
                          });

        // The last few collapses (under 1/kLastShare of the triangles) go to the blocks by
        // their edges not remembered as refused, cheapest first in each, with no threshold:
        // when a threshold is left to find them, each pass over the whole mesh makes only a
        // handful. (A tenth left one pass of 9,000 collapses for a needed 49,000 on the t0.50
        // 1.69M frame; a fifth saves it, 4% of the chain's work, with the same fidelity.) Shared
        // by block size instead, most of the budget went to blocks where every edge left is
        // refused: 15 passes for the last 9,000 collapses on that frame.
        const bool last = countTarget && needed * kLastShare < n;
        const Shares shares =
            countTarget ? shareOut(s, blocks, target.maxError, needed, last, rankFactor)
                        : Shares{target.maxError, true, std::vector<size_t>(nb, SIZE_MAX)};
        const std::vector<size_t>& budget = shares.budget;

        std::vector<BlockResult> results(nb);
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, nb, 1), [&](const tbb::blocked_range<size_t>& r) {
                for (size_t b = r.begin(); b != r.end(); ++b) {
                    if (budget[b] == 0) {
                        for (size_t i = blockStart[b]; i < blockStart[b + 1]; ++i) {
                            results[b].triangles.push_back(s.triangles[tris[i]]);
                            results[b].remembered.push_back(s.refused[tris[i]]);
                        }
                        continue;
                    }
                    Block block(s, &tris[blockStart[b]], blockStart[b + 1] - blockStart[b], valence,
                                localOf.local());
                    results[b] = block.run(shares.threshold, target, budget[b]);
                }
            });
        size_t collapses = 0;
        std::vector<size_t> offset(nb + 1, 0); // where each block's triangles go, in block order
        for (size_t b = 0; b < nb; ++b) {
            const BlockResult& r = results[b];
            collapses += r.collapses;
            st.refused += r.refused;
            st.maxError = std::max(st.maxError, r.maxError);
            st.maxDrift = std::max(st.maxDrift, r.maxDrift);
            offset[b + 1] = offset[b] + r.triangles.size();
            for (uint32_t v : r.touched)
                touched[v] = 1;
        }
        s.triangles.resize(offset[nb]);
        s.refused.resize(offset[nb]);
        tbb::parallel_for(size_t(0), nb, [&](size_t b) {
            std::copy(results[b].triangles.begin(), results[b].triangles.end(),
                      s.triangles.begin() + std::ptrdiff_t(offset[b]));
            std::copy(results[b].remembered.begin(), results[b].remembered.end(),
                      s.refused.begin() + std::ptrdiff_t(offset[b]));
            results[b] = BlockResult();
        });
        forgetTouched(s, touched);
        st.collapses += collapses;
        st.passes = pass + 1;
        if (!countTarget) {
            // everything under the bound was tried: once with each block offset is enough
            // unless a pass still finds work
            if (pass >= 1 && collapses <= n / 1000) break;
        } else if (shares.allEdges) {
            idle = collapses ? 0 : idle + 1;
            if (idle == 2) break; // nothing left that the guards allow, with either offset
        } else if (4 * collapses < needed) {
            rankFactor *= 2; // collapses are refused or blocked more than expected
        }
    }

    TriangleMesh out = compact(s, kept);
    if (stats) *stats = st; // no normals: see Normals.h
    return out;
}

} // namespace post
} // namespace fluidsurf
