// DecimateBlock.h - one block's greedy edge collapses for the parallel decimation (Decimate.cc,
// which cuts the mesh into blocks and runs the passes), and the mesh state the blocks share.
// Only Decimate.cc includes it (and RankHeapTest, for the heap).
//
// Each collapse moves the edge to the point of least quadric error (not to one of its ends, as
// OpenMesh does, as a rule): the error is measured against the original triangles' planes, which
// averages out the particles' bumps on flat fluid. Where that point would leave a sliver or a fold
// (the shape guards below), the edge's middle is tried, then either end, and the first that keeps
// the shapes is taken, if its own error is within the pass' threshold: marching cubes' slivers
// around an edge refused the quadric's point for most edges late in the decimation (2.3M
// thin-angle refusals against 1.6M collapses on the 1.7M-particle frame), and each refused try
// was work for nothing. With the others tried too, that decimation takes a fifth less time and
// the processed meshes have a quarter to a half as many thin triangles, within the same bounds
// (BENCHMARKS.md). Guards refuse a collapse that would
// - break manifoldness: the ends must share exactly the two neighbours across the edge (the
//   link condition), and no vertex may be left with fewer than three triangles;
// - turn a remaining triangle's normal by more than kMaxTurnDegrees (a fold or flip);
// - leave a triangle with an angle under kThinAngleDegrees (MeshCheck.h: what checkMesh counts
//   as thin) that was not already thinner (slivers);
// - carry a vertex farther from the input than DecimateTarget::maxDrift (see State::drift);
// - move the surface by more than DecimateTarget::maxStep, either way (post/StepGuard: the new
//   point, the old ends and triangle middles, and the new edges' middles).
// The shape guards run first (for each point tried; post/ShapeGuard, the fans set up once for
// all the points): they refuse nine collapses in ten of those refused, and cheaply.
//
// A refusal is remembered across passes (State::refused): the guards read only the two ends'
// fans, so an edge refused once is refused again until a collapse changes a fan it reads (a
// collapse's vertex and its neighbours are "touched"). Near a count target the cheapest edges
// left are mostly refused ones; without the memory, every late pass tried them all again (15
// passes of 0.03-0.3 s for 9,000 collapses on the t0.50 1.69M frame). A remembered edge is
// left out of its block's heap and put in only when a collapse touches an end while the heap
// still holds the edge in pop order (Block::touch): the collapses made are the same, in the
// same order, as with every edge in the heap.
#pragma once

#include "post/CollapseBatch.h"
#include "post/Decimate.h"
#include "post/Quadric.h"
#include "post/ShapeGuard.h"
#include "post/StepGuard.h"

#include "util/Memory.h"

#include <fluidsurf/Mesh.h>
#include <fluidsurf/MeshCheck.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <limits>
#include <memory>
#include <utility>
#include <vector>

namespace fluidsurf {
namespace post {
namespace detail {

using Tri = std::array<uint32_t, 3>;

constexpr size_t kMaxFan = 64; ///< vertices with more triangles are left alone
constexpr uint32_t kNone = UINT32_MAX;
/// Block::run rids its heap of the stale entries when about this share of it is: they were
/// four in five of the pops, each a sift from the top to a leaf, where a pass over the heap
/// drops them and makes the rest a heap again in linear time. The live entries pop in the same
/// order, and so does what Block::touch compares with (the last entry popped: a stale entry
/// only pops before a live one that ranks after it, with no push between).
constexpr size_t kPurgeShare = 1;

/// The whole mesh between passes, points relative to the middle of its bounds.
struct State
{
    Vec3d middle{0.0}; ///< of the input's bounds
    util::NoInitVector<Vec3d> points;
    /// One a point, relative to it (see makeState): the planes of the input triangles it
    /// stands for. Packed in floats: the largest array here (a double one was 169 MB on the
    /// 1.7M-particle frame).
    std::unique_ptr<PackedQuadric[]> quadrics;
    /// How far each vertex may be from the input surface it stands for: 0 for an input vertex;
    /// a collapse adds its point's largest distance to the planes of the triangles it replaces
    /// to the larger drift of its two ends (an upper bound along the normals, where the
    /// quadric's mean can hide a tip pulled in by a few voxels).
    util::NoInitVector<float> drift;
    std::vector<Tri> triangles;
    /// Per point, how many triangle corners it is (its triangles, a triangle with a corner twice
    /// counted twice): counted once, from the set-up's vertex -> triangle tables, and kept up to
    /// date by the blocks (Block::run), where each pass counted them again over every triangle,
    /// with an atomic add a corner (45 ms of the 13.1M drop's decimation on 2 cores).
    util::NoInitVector<uint32_t> valence;
    /// Per triangle, bit k: its edge (t[k], t[k + 1]) was refused, and no collapse has touched
    /// either end since (see the top of the file).
    util::NoInitVector<uint8_t> refused;
};

/// The planes of two vertices (their quadrics qa and qb, each about its own point), their
/// origin moved to `to`.
inline Quadric mergedQuadric(const Quadric& qa, const Vec3d& pa, const Quadric& qb, const Vec3d& pb,
                             const Vec3d& to)
{
    return qa.movedTo(to - pa) + qb.movedTo(to - pb);
}

struct BlockResult
{
    /// What is left of the block's triangles, with their State::refused: written over the
    /// block's own first `alive` triangles (in the block's order), in place in State.
    size_t alive = 0;
    /// Vertices the block does not own that its collapses touched: their remembered refusals
    /// in other blocks are forgotten after the pass.
    std::vector<uint32_t> touched;
    /// Vertices the block does not own that lost triangles in it, and how many: their
    /// State::valence goes down by as many after the pass.
    std::vector<std::pair<uint32_t, uint32_t>> lost;
    size_t collapses = 0, refused = 0;
    double maxError = 0, maxDrift = 0;
};

/// Vertex numbers local to a block, in the order they first appear: an open-addressing table
/// sized by the block, one per thread and reused, instead of an array as long as the mesh (4
/// bytes a vertex and a thread: 104 MB on 16 threads for a 1.7M-particle frame). Sized by the
/// vertices numbered so far, at most half full: a table for three distinct vertices a triangle
/// (the most a block can have) was twelve times a closed mesh's needs, and its look-ups missed
/// the cache (a fifth of a block's set-up). The numbers do not depend on the table's size.
class LocalNumbers
{
public:
    /// Empty, for a block of about `triangles` triangles.
    void reset(size_t triangles)
    {
        size_t size = 64;
        while (size < triangles + 64) // a closed mesh has about half as many vertices
            size <<= 1;
        mSlots.assign(size, Slot{kNone, 0});
        mMask = size - 1;
    }
    /// v's number: the one it got, or the next (v appended to global).
    uint32_t number(uint32_t v, std::vector<uint32_t>& global)
    {
        for (size_t h = slotOf(v);; h = (h + 1) & mMask) {
            Slot& s = mSlots[h];
            if (s.key == v) return s.value;
            if (s.key == kNone) {
                s = Slot{v, uint32_t(global.size())};
                global.push_back(v);
                if (2 * global.size() > mSlots.size()) grow(global);
                return uint32_t(global.size() - 1);
            }
        }
    }

private:
    struct Slot
    {
        uint32_t key, value; // side by side: one cache line a probe
    };
    size_t slotOf(uint32_t v) const { return (v * size_t(0x9E3779B1u)) >> 7 & mMask; }
    /// Twice the size, the numbers in `global` put back.
    void grow(const std::vector<uint32_t>& global)
    {
        mSlots.assign(2 * mSlots.size(), Slot{kNone, 0});
        mMask = mSlots.size() - 1;
        for (size_t k = 0; k < global.size(); ++k) {
            size_t h = slotOf(global[k]);
            while (mSlots[h].key != kNone)
                h = (h + 1) & mMask;
            mSlots[h] = Slot{global[k], uint32_t(k)};
        }
    }

    std::vector<Slot> mSlots;
    size_t mMask = 0;
};

/// A 4-ary min-heap of T by T::rank() (distinct entries have distinct ranks, so the pops come
/// in one order whatever the heap's layout). Why not std::priority_queue: its sift-down chooses
/// each level's child with a branch that goes either way at random; here the choice is a select
/// and the pop sifts its hole to a leaf first (Floyd), a third fewer compares. Four children a
/// node: half the levels of a binary heap, for three compares a level. Block's heap was an
/// eighth of the decimation's time; most entries go stale before they pop, and removeIf drops
/// them in bulk (see kPurgeShare).
template <typename T> class RankHeap
{
public:
    /// The heap of `items`, in O(n).
    void assign(std::vector<T>&& items)
    {
        mItems = std::move(items);
        heapify();
    }
    /// Drops the entries `gone` says are gone, and makes a heap of the rest, in O(n): the rest
    /// pop in the same order as they would have.
    template <typename Gone> void removeIf(Gone gone)
    {
        mItems.erase(std::remove_if(mItems.begin(), mItems.end(), gone), mItems.end());
        heapify();
    }
    bool empty() const { return mItems.empty(); }
    size_t size() const { return mItems.size(); }
    const T& top() const { return mItems.front(); }
    void push(const T& x)
    {
        size_t i = mItems.size();
        mItems.push_back(x);
        siftUp(0, i, x);
    }
    void pop()
    {
        const T x = mItems.back();
        mItems.pop_back();
        if (!mItems.empty()) siftDown(0, x);
    }

private:
    static constexpr size_t kArity = 4;

    void heapify()
    {
        for (size_t i = mItems.size() / kArity + 1; i-- > 0;)
            if (kArity * i + 1 < mItems.size()) siftDown(i, mItems[i]);
    }

    /// x into the hole at i, which moves to a leaf along the smallest children and then up.
    void siftDown(size_t i, const T x)
    {
        const size_t n = mItems.size(), start = i;
        for (size_t c = kArity * i + 1; c + kArity <= n; c = kArity * i + 1) {
            const size_t low = c + (mItems[c + 1].rank() < mItems[c].rank()),
                         high = c + 2 + (mItems[c + 3].rank() < mItems[c + 2].rank());
            const size_t m = mItems[high].rank() < mItems[low].rank() ? high : low;
            mItems[i] = mItems[m];
            i = m;
        }
        if (const size_t c = kArity * i + 1; c < n) { // the last node with children: 1 to 3
            size_t m = c;
            for (size_t k = c + 1; k < n; ++k)
                m = mItems[k].rank() < mItems[m].rank() ? k : m;
            mItems[i] = mItems[m];
            i = m;
        }
        siftUp(start, i, x);
    }
    /// x into the hole at i, moving up while its parent ranks after it (not above `top`).
    void siftUp(size_t top, size_t i, const T& x)
    {
        while (i > top) {
            const size_t parent = (i - 1) / kArity;
            if (!(x.rank() < mItems[parent].rank())) break;
            mItems[i] = mItems[parent];
            i = parent;
        }
        mItems[i] = x;
    }

    std::vector<T> mItems;
};

/// One block's greedy collapses (see the top of the file). Reads the points and quadrics of
/// every vertex of its triangles, writes only those of the vertices it owns.
class Block
{
public:
    /// `local`: one per thread.
    Block(State& s, const uint32_t* tris, size_t n, LocalNumbers& local) : mS(s), mSlots(tris)
    {
        // local vertices in the order they first appear in the block's triangles (which are in
        // mesh order): the same numbering every run, without a sort
        mTris.resize(n);
        mRefused.resize(n);
        local.reset(n);
        for (size_t i = 0; i < n; ++i) {
            mRefused[i] = s.refused[tris[i]];
            for (int k = 0; k < 3; ++k)
                mTris[i][k] = local.number(s.triangles[tris[i]][k], mGlobal);
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
        mCountBefore = mCount;
        mRefs.resize(3 * n);
        std::vector<uint32_t> fill(mStart.begin(), mStart.end() - 1);
        for (size_t t = 0; t < n; ++t)
            for (uint32_t v : mTris[t])
                mRefs[fill[v]++] = uint32_t(t);
        mStart.pop_back();
        mOwn.resize(nv);
        mMark.assign(nv, 0);
        mFanAt.resize(nv);
        for (size_t v = 0; v < nv; ++v)
            mOwn[v] = mCount[v] == s.valence[mGlobal[v]] && isClosedFan(uint32_t(v));
        mChangedAt.assign(nv, 0);
        mMayRefuse.assign(nv, 0);
        for (size_t t = 0; t < n; ++t)
            for (int k = 0; k < 3; ++k)
                if (mRefused[t] >> k & 1)
                    mMayRefuse[mTris[t][k]] = mMayRefuse[mTris[t][(k + 1) % 3]] = 1;
        mQuadric.resize(nv);
        for (size_t v = 0; v < nv; ++v)
            mQuadric[v] = s.quadrics[mGlobal[v]].unpack();
        mPoint.resize(nv);
        for (size_t v = 0; v < nv; ++v)
            mPoint[v] = s.points[mGlobal[v]];
        mDrift.resize(nv);
        for (size_t v = 0; v < nv; ++v)
            mDrift[v] = s.drift[mGlobal[v]];
    }

    BlockResult run(double threshold, const DecimateTarget& target, size_t budget)
    {
        BlockResult out;
        mThreshold = threshold, mMaxDrift = target.maxDrift, mMaxStep = target.maxStep;
        mStep = StepGuard(mMaxStep);
        std::vector<Entry> entries; // made a heap at once: cheaper than pushing one by one
        entries.reserve(3 * mTris.size() / 2);
        mFound.clear();
        mFound.reserve(3 * mTris.size() / 2 + 8 * std::min(budget, mTris.size()));
        mEdges.clear();
        for (size_t t = 0; t < mTris.size(); ++t)
            for (int k = 0; k < 3; ++k) { // each inner edge once, from its lower end
                const uint32_t a = mTris[t][k], b = mTris[t][(k + 1) % 3];
                if (a < b && !(mRefused[t] >> k & 1) && mOwn[a] && mOwn[b])
                    mEdges.push_back({a, b});
            }
        pushEdges(&entries);
        mHeap.assign(std::move(entries));
        mPopped = false;
        auto stale = [&](const Entry& e) {
            return e.found < mChangedAt[uint32_t(e.key)] || e.found < mChangedAt[e.b];
        };
        mStale = 0;
        while (!mHeap.empty() && out.collapses < budget) {
            if (mStale > kPurgeShare * mHeap.size()) {
                mHeap.removeIf(stale); // (see kPurgeShare)
                mStale = 0;
                if (mHeap.empty()) break;
            }
            const Entry e = mHeap.top();
            mHeap.pop();
            if (popsAfterLast(e)) mLast = e, mPopped = true;
            const uint32_t a = uint32_t(e.key);
            if (stale(e)) continue; // an end changed
            double error = 0;
            const Outcome o = collapse(a, e.b, mFound[e.found], error);
            if (o == Outcome::Collapsed) {
                ++out.collapses;
                out.maxError = std::max(out.maxError, error);
                out.maxDrift = std::max(out.maxDrift, double(mDrift[a]));
                for (uint32_t w : mRing) // after collapse(): touch() walks with mMark too
                    touch(w, a, out.touched);
            } else {
                ++out.refused;
            }
        }
        // the valences its collapses changed (State::valence): a vertex the block owns, or
        // owned and merged away (none that it does not own is left without a triangle here:
        // collapse()), has all its triangles here, and no other block reads or writes its
        // count; one it does not own may be read by blocks still to start in this pass, and
        // lose triangles in other blocks too: what it lost here is applied after the pass
        // (BlockResult::lost)
        for (size_t v = 0; v < mCount.size(); ++v) {
            if (mCount[v] == mCountBefore[v]) continue;
            if (mOwn[v] || mCount[v] == 0)
                mS.valence[mGlobal[v]] = mCount[v];
            else
                out.lost.push_back({mGlobal[v], mCountBefore[v] - mCount[v]});
        }
        // in place: the block read its triangles once, in the constructor, and no other block
        // reads them (a per-block copy left its holes in the threads' heaps: 100 MB resident)
        for (size_t t = 0; t < mTris.size(); ++t)
            if (mTriAlive[t]) {
                const uint32_t slot = mSlots[out.alive++];
                mS.triangles[slot] = {mGlobal[mTris[t][0]], mGlobal[mTris[t][1]],
                                      mGlobal[mTris[t][2]]};
                mS.refused[slot] = mRefused[t];
            }
        return out;
    }

private:
    /// 16 bytes, one integer compare as a rule: the heap's sifting is a tenth of the work.
    struct Entry
    {
        // Laid out as the 128-bit rank itself, lowest bits first (x86-64 is little-endian): the
        // heap's compares load it as it lies, where shifting the fields together was 3% of the
        // decimation's instructions.
        /// The collapse's place in mFound, which only grows: the entry is stale once an end
        /// has changed after it was pushed (mChangedAt).
        uint32_t found;
        uint32_t b;
        /// the error as a float (its bits order like the value: it is >= 0), then the lower
        /// end: the heap's top is the smallest error, ties to the lowest ends, one order every run
        uint64_t key;
        /// The heap's order: the smallest error first, ties to the lowest ends (and, for one
        /// edge pushed twice with one error, the older push, which is stale by then):
        /// key << 64 | b << 32 | found.
        unsigned __int128 rank() const
        {
            unsigned __int128 r;
            std::memcpy(&r, this, sizeof r);
            return r;
        }
        /// Pops after o, the push aside.
        bool after(const Entry& o) const { return key != o.key ? key > o.key : b > o.b; }
    };
    static_assert(sizeof(Entry) == 16 && offsetof(Entry, b) == 4 && offsetof(Entry, key) == 8 &&
                      __BYTE_ORDER__ == __ORDER_LITTLE_ENDIAN__,
                  "Entry::rank reads the fields as one little-endian 128-bit number");

    enum class Outcome {
        Collapsed,
        Refused, ///< by the ends' fans alone: remembered (State::refused)
        /// by what lies outside the fans too, or dearer than the pass' threshold at the point
        /// taken: tried again next time
        RefusedUnstable,
    };

    const Vec3d& point(uint32_t v) const { return mPoint[v]; }

    /// bestCollapse of the local edge (a, b), from the block's unpacked quadrics.
    Collapse bestCollapse(uint32_t a, uint32_t b) const
    {
        return detail::bestCollapse(mQuadric[a], point(a), mQuadric[b], point(b));
    }

    /// v's triangles (its list holds only live ones: a collapse drops the two that go from
    /// the lists of the corners across the edge, and a's is made anew).
    void aliveTris(uint32_t v, std::vector<uint32_t>& out) const
    {
        out.assign(mRefs.begin() + mStart[v], mRefs.begin() + mStart[v] + mCount[v]);
    }

    /// v's triangles go once around it, a disc: each triangle's far side leads to the next.
    /// Each corner after v is looked up by a stamp (mMark, mFanAt), not searched for (the
    /// search was a tenth of a block's set-up's instructions).
    bool isClosedFan(uint32_t v)
    {
        const uint32_t n = mCount[v];
        if (n < 3 || n > kMaxFan) return false;
        const uint32_t stamp = ++mStamp;
        uint32_t to[kMaxFan], first = kNone;
        for (uint32_t i = 0; i < n; ++i) {
            const Tri& t = mTris[mRefs[mStart[v] + i]];
            const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
            const uint32_t from = t[(k + 1) % 3];
            if (mMark[from] == stamp) return false; // two triangles from one corner: not a disc
            mMark[from] = stamp, mFanAt[from] = uint8_t(i);
            to[i] = t[(k + 2) % 3];
            if (i == 0) first = from;
        }
        uint32_t cur = first;
        uint64_t seen = 0;
        for (uint32_t step = 0; step < n; ++step) {
            if (mMark[cur] != stamp) return false; // the fan is open
            const uint32_t i = mFanAt[cur];
            if (seen >> i & 1) return false; // not one fan
            seen |= uint64_t(1) << i;
            cur = to[i];
            if ((cur == first) != (step == n - 1)) return false; // back too soon or never
        }
        return true;
    }

    /// The heap entry of edge (a, b), a < b, whose collapse `found` would make, if it belongs
    /// in the heap; the collapse goes into mFound when the entry goes in (add).
    bool entry(uint32_t a, uint32_t b, const Collapse& found, Entry& e) const
    {
        if (!(found.error <= mThreshold)) return false;
        const float key = float(found.error);
        uint32_t bits;
        std::memcpy(&bits, &key, sizeof bits);
        e = Entry{uint32_t(mFound.size()), b, uint64_t(bits) << 32 | a};
        return true;
    }

    /// e into `entries` (else the heap), with the collapse it stands for: the pop finds the
    /// point there instead of solving for it again (an edge is tried once for every time it
    /// is pushed, as a rule, and the solve was 6% of the decimation's instructions).
    void add(const Entry& e, const Collapse& found, std::vector<Entry>* entries = nullptr)
    {
        mFound.push_back(found);
        entries ? entries->push_back(e) : mHeap.push(e);
    }

    /// The edges in mEdges (owned ends, the lower first) that belong in the heap, into
    /// `entries` (else the heap), their collapses found a batch at a time.
    void pushEdges(std::vector<Entry>* entries = nullptr)
    {
        for (size_t i = 0; i < mEdges.size(); i += CollapseBatch::kSize) {
            const int n = int(std::min<size_t>(CollapseBatch::kSize, mEdges.size() - i));
            for (int l = 0; l < n; ++l) {
                const auto [a, b] = mEdges[i + l];
                mBatch.set(l, mQuadric[a], point(a), mQuadric[b], point(b));
            }
            Collapse found[CollapseBatch::kSize];
            mBatch.collapses(n, found);
            for (int l = 0; l < n; ++l) {
                Entry e;
                if (entry(mEdges[i + l].first, mEdges[i + l].second, found[l], e))
                    add(e, found[l], entries);
            }
        }
    }

    /// e comes after every entry popped so far (the heap's order: the top is the largest).
    bool popsAfterLast(const Entry& e) const { return !mPopped || e.after(mLast); }

    /// Remembers the refusal of edge (a, b) on both its triangles.
    Outcome refuse(uint32_t a, uint32_t b, const uint32_t (&shared)[2])
    {
        mMayRefuse[a] = mMayRefuse[b] = 1;
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
        if (!mMayRefuse[u]) return; // nothing remembered at u (most ring vertices)
        mMayRefuse[u] = 0;          // all of u's forgotten below
        const uint32_t stamp = ++mStamp;
        for (uint32_t i = mStart[u]; i < mStart[u] + mCount[u]; ++i) {
            const uint32_t t = mRefs[i];
            if (!mTriAlive[t] || !mRefused[t]) continue;
            for (int k = 0; k < 3; ++k) {
                const uint32_t p = mTris[t][k], q = mTris[t][(k + 1) % 3];
                if (!(mRefused[t] >> k & 1) || (p != u && q != u)) continue;
                mRefused[t] &= uint8_t(~(1 << k));
                const uint32_t v = p == u ? q : p;
                if (v == a || mMark[v] == stamp || !mOwn[v]) continue;
                mMark[v] = stamp;
                const uint32_t lo = std::min(u, v), hi = std::max(u, v);
                const Collapse found = bestCollapse(lo, hi);
                Entry e;
                if (entry(lo, hi, found, e) && popsAfterLast(e)) add(e, found);
            }
        }
    }

    /// The triangles of the two fans that stay if edge (a, b) goes, into mFan (a's, then b's
    /// from mSecondFan; each (v, u, w) in its own order, with only v moving) and into the shape
    /// guard: found once for every point the collapse tries.
    void fanOf(uint32_t a, uint32_t b, const uint32_t (&shared)[2])
    {
        mFan.clear();
        mShapes.clear();
        for (const uint32_t v : {a, b}) {
            if (v == b) mSecondFan = mFan.size();
            const Vec3d x = point(v);
            for (uint32_t t : v == a ? mTa : mTb) {
                if (t == shared[0] || t == shared[1]) continue;
                const Tri& tri = mTris[t];
                const int k = tri[0] == v ? 0 : tri[1] == v ? 1 : 2;
                const Tri ids{v, tri[(k + 1) % 3], tri[(k + 2) % 3]};
                const Vec3d& u = point(ids[1]);
                const Vec3d& w = point(ids[2]);
                const Vec3d n0 = (u - x).cross(w - x);
                // (written in place, field by field: made whole on the stack and then copied,
                // two of the copy's 16-byte loads straddled the 8-byte stores that had made it
                // and waited for them, unforwarded; about 1% of the decimation's time)
                FanTriangle& f = mFan.emplace_back();
                f.t = t, f.ids = ids, f.u = u, f.w = w, f.n0 = n0;
                mShapes.add(x, u, w, n0);
            }
        }
    }

    /// Tries the collapse of edge (a, b), col its bestCollapse (a copy, as mFound grows below;
    /// changed where another point is taken).
    Outcome collapse(uint32_t a, uint32_t b, Collapse col, double& error)
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
        // the shapes first: they refuse most collapses (nine in ten refused), and cheaply: in
        // squares, without roots. The quadric's point, else the middle, else an end (see the
        // top of the file).
        const Vec3d& pa = point(a);
        const Vec3d& pb = point(b);
        const Vec3d tries[4] = {col.point, (pa + pb) * 0.5, pa, pb};
        fanOf(a, b, shared);
        int taken = -1;
        for (int i = 0; i < 4 && taken < 0; ++i)
            if (mShapes.keeps(tries[i])) taken = i;
        if (taken < 0) return refuse(a, b, shared);
        if (taken > 0) {
            col.point = tries[taken];
            const Quadric m = mergedQuadric(mQuadric[a], pa, mQuadric[b], pb, col.point);
            col.error = m.w > 0 ? m.c / m.w : 0; // (c: the planes' error at the point)
            // dearer than the pass allows: tried again in a later pass (not remembered)
            if (!(col.error <= mThreshold)) return Outcome::RefusedUnstable;
        }
        const Vec3d& q = col.point;
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
        for (uint32_t c : opposite) // each loses one triangle (c's fan: not remembered)
            if (mCount[c] - 1 < (mOwn[c] ? 3u : 2u)) return Outcome::RefusedUnstable;
        // how far the surface moves: the drift bound, and the fans for withinStep
        const bool stepBound = mMaxStep < std::numeric_limits<double>::infinity();
        double drift = 0; // see State::drift
        // (a plane of the old fan is as far off the input as its corners may be)
        auto far = [&](const Tri& t) {
            return double(std::max({mDrift[t[0]], mDrift[t[1]], mDrift[t[2]]}));
        };
        auto driftTo = [&](const Vec3d& x, const Vec3d& n0, const Tri& t) {
            const double l0 = n0.length();
            if (l0 > 0) drift = std::max(drift, std::abs(n0.dot(q - x)) / l0 + far(t));
        };
        // the two that go (see StepGuard), then the others as the shape guard saw them
        std::array<Vec3d, 4> gone[2];
        Vec3d acrossPoints[2];
        for (int g = 0; g < 2; ++g) {
            const Tri& tri = mTris[shared[g]];
            const Vec3d &x = point(tri[0]), &u = point(tri[1]), &w = point(tri[2]);
            gone[g] = {x, u, w, (u - x).cross(w - x)};
            acrossPoints[g] = point(opposite[g]);
            driftTo(x, gone[g][3], tri);
        }
        for (size_t i = 0; i < mFan.size(); ++i)
            driftTo(i < mSecondFan ? pa : pb, mFan[i].n0, mTris[mFan[i].t]);
        if (drift > mMaxDrift) return refuse(a, b, shared);
        if (stepBound) {
            const Tri goneIds[2] = {mTris[shared[0]], mTris[shared[1]]};
            mStep.start(q, gone, goneIds, opposite, acrossPoints);
            if (!mStep.accepts(pa, pb, mFan.data(), mFan.size(), mSecondFan))
                return refuse(a, b, shared);
        }
        error = col.error;

        // commit: b merges into a
        mS.quadrics[mGlobal[a]] = PackedQuadric::pack(
            mergedQuadric(mQuadric[a], point(a), mQuadric[b], point(b), col.point));
        mQuadric[a] = mS.quadrics[mGlobal[a]].unpack(); // as the state keeps it
        mPoint[a] = mS.points[mGlobal[a]] = col.point;
        mDrift[a] = mS.drift[mGlobal[a]] = float(drift);
        mTriAlive[shared[0]] = mTriAlive[shared[1]] = 0;
        for (uint32_t c : opposite) { // the dead out of c's list, the order kept
            uint32_t* list = &mRefs[mStart[c]];
            uint32_t kept = 0;
            for (uint32_t i = 0; i < mCount[c]; ++i)
                if (mTriAlive[list[i]]) list[kept++] = list[i];
            mCount[c] = kept;
        }
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
        mStale += mTa.size() + mTb.size(); // about the entries of a's and b's edges
        mChangedAt[a] = mChangedAt[b] = uint32_t(mFound.size()), mOwn[b] = 0;
        const uint32_t mark = ++mStamp;
        mRing.clear();
        mEdges.clear();
        for (uint32_t i = mStart[a]; i < mStart[a] + mCount[a]; ++i) {
            const uint32_t t = mRefs[i];
            for (uint32_t w : mTris[t])
                if (w != a && mMark[w] != mark) {
                    mMark[w] = mark, mRing.push_back(w);
                    if (mOwn[w]) mEdges.push_back({std::min(a, w), std::max(a, w)});
                }
            for (int k = 0; k < 3; ++k) // a's own edges are all in the heap again
                if (mTris[t][k] == a || mTris[t][(k + 1) % 3] == a)
                    mRefused[t] &= uint8_t(~(1 << k));
        }
        pushEdges();
        return Outcome::Collapsed;
    }

    State& mS;
    const uint32_t* mSlots;        ///< the block's triangles in State
    std::vector<uint32_t> mGlobal; ///< local vertex -> mesh vertex
    std::vector<Tri> mTris;        ///< in local vertices
    std::vector<uint8_t> mTriAlive, mOwn;
    std::vector<uint8_t> mRefused;               ///< State::refused, per local triangle
    std::vector<uint32_t> mStart, mCount, mRefs; ///< vertex -> its triangles (lists grow at
                                                 ///< the end of mRefs as vertices merge)
    std::vector<uint32_t> mCountBefore;          ///< mCount as the block began (see run)
    /// per vertex: mFound's size when it last moved or went (entries found before are stale)
    std::vector<uint32_t> mChangedAt;
    /// the collapses of the entries pushed, in the order pushed (Entry::found)
    std::vector<Collapse> mFound;
    /// per vertex: it may have an edge remembered as refused (0: it has none; touch skips it)
    std::vector<uint8_t> mMayRefuse;
    /// State::quadrics unpacked, per local vertex: each edge's error reads two, and unpacking
    /// them was a seventh of the quadric work (only owned vertices change, here and in State).
    std::vector<Quadric> mQuadric;
    /// State::points per local vertex, the same way (read through the mesh's numbers, they
    /// were an extra load and a cache miss at every corner the guards look at).
    std::vector<Vec3d> mPoint;
    /// State::drift per local vertex, the same way (read at every corner of a collapse's fans:
    /// through the mesh's numbers, each was a load from an array as long as the mesh).
    std::vector<float> mDrift;
    RankHeap<Entry> mHeap;
    /// About how many of the heap's entries are stale: the edges of the ends of the collapses
    /// since the heap was last rid of them (run).
    size_t mStale = 0;
    double mThreshold = 0, mMaxDrift = 0, mMaxStep = 0;
    StepGuard mStep{0};          ///< the fans of the collapse being tried (DecimateTarget::maxStep)
    std::vector<uint32_t> mMark; ///< per vertex: the stamp of the last neighbour walk it was in
    std::vector<uint8_t> mFanAt; ///< per vertex: its triangle in isClosedFan's fan
    uint32_t mStamp = 0;
    std::vector<uint32_t> mTa, mTb; // scratch
    /// The remaining triangles of the collapse being tried, for all its guards: a's fan, then
    /// b's from mSecondFan.
    std::vector<FanTriangle> mFan;
    size_t mSecondFan = 0;
    ShapeGuard mShapes;          ///< the same triangles, for the shape guards (fanOf)
    std::vector<uint32_t> mRing; ///< the last collapse's vertex' neighbours
    std::vector<std::pair<uint32_t, uint32_t>> mEdges; ///< edges for pushEdges
    CollapseBatch mBatch;
    Entry mLast{}; ///< the last entry popped in heap order (see touch)
    bool mPopped = false;
};

} // namespace detail
} // namespace post
} // namespace fluidsurf
