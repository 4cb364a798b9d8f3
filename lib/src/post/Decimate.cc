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
//   as refused (DecimateBlock.h), cheapest first in each.
// - Why not one serial heap (the textbook greedy): measured on the real frames, it pulled thin
//   tips in by 2-4 voxels whatever the weights or placement, where the passes keep them.
//
// Each block's collapses, the guards and the memory of refusals: post/DecimateBlock.h.
//
// Set-up costs count on two cores: a block numbers its vertices in the order they first appear
// (a per-thread table, not a sort), the blocks are found by a counting sort, and the quadrics are
// gathered per vertex in parallel.
#include "post/Decimate.h"

#include "post/DecimateBlock.h"
#include "post/Normals.h"
#include "post/PlaneQuadrics.h"

#include "util/Floor.h"
#include "util/MarkedNumbers.h"
#include "util/Memory.h"
#include "util/NthSmallest.h"
#include "util/TriangleDistance.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <functional>
#include <limits>
#include <utility>

namespace fluidsurf {
namespace post {
namespace {

using namespace detail;

constexpr double kBlockEdges = 32; ///< a block's side in mean edge lengths (~2,500 triangles)
constexpr size_t kMaxPasses = 64;
constexpr size_t kLastShare = 5;  ///< see "last" in decimate()
constexpr size_t kSample = 4;     ///< a pass' threshold from every kSample-th triangle's edges
constexpr size_t kTableParts = 2; ///< makeState's vertex -> triangle table, in this many parts
constexpr uint8_t kGone = 0x80;   ///< State::refused of a triangle a pass collapsed away

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
    // The input's points and normals go before the vertex -> triangle table and the quadrics
    // are allocated: 24 bytes a vertex less at the peak.
    std::vector<Vec3f>().swap(mesh.normals); // not used here (the result gets new ones)
    util::resizeInParallel(s.points, nv);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v)
            s.points[v] = toVec3d(mesh.points[v]) - s.middle;
    });
    std::vector<Vec3f>().swap(mesh.points); // s.points has them
    s.triangles = std::move(mesh.triangles);
    // (the state's arrays are NoInitVectors, filled here on all threads: zeroed by one thread,
    // they took 0.024 s of the state's set-up at any thread count, a third of it on 16)
    s.refused.resize(s.triangles.size());
    util::fillInParallel(s.refused, uint8_t(0));
    s.drift.resize(nv);
    util::fillInParallel(s.drift, 0.f);
    // each vertex gathers the planes of its triangles, weighted by area, in triangle order: the
    // same sums every run. The vertex -> triangle table is made for a part of the vertices at
    // a time: whole, it was the peak of the run (45 MB on the 1.7M-particle frame). Each part
    // reads every triangle twice: in halves rather than quarters, 8 ms less on 2 cores for
    // the 13.1M drop, for a peak a few MB higher on the 1.7M-particle frame (161 -> 164-181
    // MB writing PLY, 3 runs; the peak moves by as much from run to run).
    // not zeroed: filled below in parallel, where its pages are first touched
    s.quadrics.reset(new PackedQuadric[nv]);
    s.valence.resize(nv); // (filled with the quadrics, from the same tables)
    for (size_t part = 0; part < kTableParts; ++part) {
        const auto first = uint32_t(nv * part / kTableParts),
                   last = uint32_t(nv * (part + 1) / kTableParts);
        const VertexTriangles around(s.triangles, first, last);
        tbb::parallel_for(
            tbb::blocked_range<uint32_t>(first, last), [&](const tbb::blocked_range<uint32_t>& r) {
                for (uint32_t v = r.begin(); v != r.end(); ++v)
                    s.valence[v] = around.start[v - first + 1] - around.start[v - first];
                planeQuadrics(s.points.data(), s.triangles, around, first, r.begin(), r.end(),
                              s.quadrics.get()); // (packed: see State)
            });
    }
    return s;
}

/// The triangles grouped by block (the cube of side `side` its centroid is in, cubes shifted by
/// `shift` sides), blocks in the order of their cube's key (x, then y, then z), triangles in
/// mesh order within each: tris[start[b], start[b + 1]) are block b's.
struct Blocks
{
    util::NoInitVector<uint32_t> tris; // (filled whole on all threads)
    std::vector<size_t> start;
};

/// A counting sort on the blocks present, numbered densely in key order: 8 bytes a triangle at
/// the peak, where a radix sort of (key, triangle) pairs took 20 (65 MB on the 1.7M-particle
/// frame, the peak of the whole run). Parallel over fixed chunks, each writing its triangles
/// from where the same block's earlier chunks end: the same result for any thread count.
Blocks sortIntoBlocks(const State& s, double side, double shift)
{
    const size_t n = s.triangles.size();
    constexpr int kBits = 10, kAxes = 3; // 10 bits an axis: 1,024 blocks across is plenty
    constexpr uint32_t kMask = (1u << kBits) - 1;
    constexpr size_t kChunk = size_t(1) << 16;
    const size_t chunks = (n + kChunk - 1) / kChunk;
    util::NoInitVector<uint32_t> block(n); // each triangle's key, then its block's number
    std::vector<std::vector<uint32_t>> present(chunks); // the keys in each chunk, sorted, once
    tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
        std::vector<uint32_t>& keys = present[c];
        for (size_t t = c * kChunk; t < std::min(n, (c + 1) * kChunk); ++t) {
            const Tri& tri = s.triangles[t];
            const Vec3d m = (s.points[tri[0]] + s.points[tri[1]] + s.points[tri[2]]) / 3.0;
            uint32_t key = 0;
            for (int k = 0; k < kAxes; ++k)
                key = key << kBits | (uint32_t(util::floorOf(m[k] / side + shift) + 512) & kMask);
            block[t] = key;
            if (keys.empty() || keys.back() != key) keys.push_back(key); // runs: few a chunk
        }
        std::sort(keys.begin(), keys.end());
        keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    });
    std::vector<uint32_t> keys;
    for (auto& p : present) {
        keys.insert(keys.end(), p.begin(), p.end());
        std::vector<uint32_t>().swap(p);
    }
    std::sort(keys.begin(), keys.end());
    keys.erase(std::unique(keys.begin(), keys.end()), keys.end());
    const size_t nb = keys.size();
    // counts per (group of chunks, block): few enough groups that the table stays under n / 8
    // entries however many blocks there are
    const size_t groups = std::max<size_t>(1, std::min(chunks, n / (8 * std::max<size_t>(nb, 1))));
    const size_t per = (n + groups - 1) / groups;
    std::vector<uint32_t> at(groups * nb, 0);
    tbb::parallel_for(size_t(0), groups, [&](size_t g) {
        uint32_t* count = &at[g * nb];
        uint32_t key = UINT32_MAX, number = 0; // the last key's number: runs are common
        for (size_t t = g * per; t < std::min(n, (g + 1) * per); ++t) {
            if (block[t] != key)
                key = block[t],
                number = uint32_t(std::lower_bound(keys.begin(), keys.end(), key) - keys.begin());
            ++count[block[t] = number];
        }
    });
    Blocks b;
    b.start.resize(nb + 1);
    size_t sum = 0;
    for (size_t k = 0; k < nb; ++k) {
        b.start[k] = sum;
        for (size_t g = 0; g < groups; ++g)
            sum += std::exchange(at[g * nb + k], uint32_t(sum));
    }
    b.start[nb] = sum;
    b.tris.resize(n);
    tbb::parallel_for(size_t(0), groups, [&](size_t g) {
        uint32_t* to = &at[g * nb];
        for (size_t t = g * per; t < std::min(n, (g + 1) * per); ++t)
            b.tris[to[block[t]]++] = uint32_t(t);
    });
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
    const util::NoInitVector<uint32_t>& tris = blocks.tris;
    const std::vector<size_t>& blockStart = blocks.start;
    Shares sh{maxError, true, std::vector<size_t>(nb, 0)};
    // the sampled edges' errors, by block order (3 for the i-th sampled triangle in block
    // order, the kSample * i-th): infinite for an edge left to its other triangle
    util::NoInitVector<float> errors; // (each written below, on all threads)
    if (!last) {
        errors.resize(3 * ((n + kSample - 1) / kSample));
        tbb::parallel_for(tbb::blocked_range<size_t>(0, errors.size() / 3),
                          [&](const tbb::blocked_range<size_t>& r) {
                              CollapseBatch batch;
                              size_t at[CollapseBatch::kSize]; // each lane's place in errors
                              int n = 0;
                              auto flush = [&] {
                                  double e[CollapseBatch::kSize];
                                  batch.errors(n, e);
                                  for (int l = 0; l < n; ++l)
                                      errors[at[l]] = float(e[l]);
                                  n = 0;
                              };
                              for (size_t i = r.begin(); i != r.end(); ++i)
                                  for (int k = 0; k < 3; ++k) {
                                      const Tri& t = s.triangles[tris[kSample * i]];
                                      const uint32_t a = t[k], b = t[(k + 1) % 3];
                                      errors[3 * i + k] = std::numeric_limits<float>::infinity();
                                      if (a > b) continue;
                                      batch.set(n, s.quadrics[a].unpack(), s.points[a],
                                                s.quadrics[b].unpack(), s.points[b]);
                                      at[n++] = 3 * i + k;
                                      if (n == CollapseBatch::kSize) flush();
                                  }
                              if (n > 0) flush();
                          });
        const double rank = rankFactor * double(needed) / kSample;
        float kth = 0; // (the errors are >= +0: Quadric::error and bestCollapse never give -0)
        if (rank < double(errors.size()) &&
            util::nthSmallest(
                errors.data(), errors.size(),
                [&](float e) { return e <= maxError && std::isfinite(e); }, size_t(rank), kth)) {
            sh.threshold = std::min(sh.threshold, double(kth));
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
                // the block's sampled triangles: kSample * i in [start, next start)
                for (size_t i = 3 * ((blockStart[b] + kSample - 1) / kSample);
                     i < 3 * ((blockStart[b + 1] + kSample - 1) / kSample); ++i)
                    under[b] += errors[i] <= sh.threshold;
    });
    size_t total = 0;
    for (size_t u : under)
        total += u;
    size_t given = 0;
    for (size_t b = 0; b < nb; ++b)
        given += sh.budget[b] = total ? size_t(double(needed) * double(under[b]) / total) : 0;
    // What rounding down left: one more each to the blocks with the most edges in play. The
    // first blocks in key order took it before, and a small one (2 triangles on the 1.7M-particle
    // frame, 26 on the 13.1M drop) could not make it: the last pass fell short by one collapse,
    // and a whole pass more over the mesh made it.
    std::vector<uint32_t> order;
    for (size_t b = 0; b < nb; ++b)
        if (under[b] > 0) order.push_back(uint32_t(b));
    const size_t extra = std::min(needed > given ? needed - given : 0, order.size());
    std::partial_sort(
        order.begin(), order.begin() + ptrdiff_t(extra), order.end(),
        [&](uint32_t a, uint32_t b) { return under[a] != under[b] ? under[a] > under[b] : a < b; });
    for (size_t i = 0; i < extra; ++i)
        ++sh.budget[order[i]];
    return sh;
}

/// The triangles not marked kGone (with their State::refused), moved down in place in order;
/// returns how many. Each fixed piece moves its own down to its start on all threads, then the
/// pieces move down one after the other, whole (one thread's pass over every triangle was 0.017 s
/// of the 13.1M drop's decimation on 16 threads).
size_t dropGone(State& s)
{
    constexpr size_t kPiece = size_t(1) << 16;
    const size_t n = s.triangles.size(), pieces = (n + kPiece - 1) / kPiece;
    std::vector<size_t> kept(pieces);
    tbb::parallel_for(size_t(0), pieces, [&](size_t p) {
        size_t to = p * kPiece;
        for (size_t t = p * kPiece; t < std::min(n, (p + 1) * kPiece); ++t)
            if (s.refused[t] != kGone)
                s.triangles[to] = s.triangles[t], s.refused[to++] = s.refused[t];
        kept[p] = to - p * kPiece;
    });
    size_t left = 0;
    for (size_t p = 0; p < pieces; ++p) { // (each lands at or below where it lies)
        if (left != p * kPiece) {
            std::memmove(&s.triangles[left], &s.triangles[p * kPiece], kept[p] * sizeof(Tri));
            std::memmove(&s.refused[left], &s.refused[p * kPiece], kept[p]);
        }
        left += kept[p];
    }
    return left;
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
/// indices in the input). The state's other arrays go first: they are the most of its bytes.
TriangleMesh compact(State&& s, std::vector<uint32_t>* kept)
{
    s.quadrics.reset();
    util::NoInitVector<uint32_t>().swap(s.valence);
    util::NoInitVector<float>().swap(s.drift);
    util::NoInitVector<uint8_t>().swap(s.refused);
    util::returnFreedMemory();
    TriangleMesh out;
    const size_t nv = s.points.size(), nt = s.triangles.size();
    util::NoInitVector<uint32_t> index(nv); // (all on all threads, the numbering too)
    util::fillInParallel(index, UINT32_MAX);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nt), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t t = r.begin(); t != r.end(); ++t)
            for (uint32_t v : s.triangles[t]) // a mark: any order, any repeat
                __atomic_store_n(&index[v], 0u, __ATOMIC_RELAXED);
    });
    const util::MarkedNumbers numbers(nv, [&](size_t v) { return index[v] == 0; });
    numbers.forEach([&](size_t v, bool used, size_t k) {
        if (used) index[v] = uint32_t(k - 1);
    });
    const size_t used = numbers.count();
    util::resizeInParallel(out.points, used);
    if (kept) util::resizeInParallel(*kept, used);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, index.size()),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t v = r.begin(); v != r.end(); ++v)
                              if (index[v] != UINT32_MAX) {
                                  out.points[index[v]] = toVec3f(s.points[v] + s.middle);
                                  if (kept) (*kept)[index[v]] = uint32_t(v);
                              }
                      });
    util::NoInitVector<Vec3d>().swap(s.points);
    util::resizeInParallel(out.triangles, nt);
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
    size_t idle = 0;       // passes in a row without a collapse
    double rankFactor = 3; // collapses under the threshold per collapse made
    std::vector<uint8_t> touched(s.points.size(), 0);      // see BlockResult::touched
    tbb::enumerable_thread_specific<LocalNumbers> localOf; // see Block
    for (size_t pass = 0; pass < kMaxPasses; ++pass) {
        // (No trim of the heap between the passes' steps (util/Memory.h): each of the three a
        // pass gave its free pages back, and the next step faulted them in again. On 16
        // threads a trim took 3 ms, the TLB of every thread's core flushed, and the 13.1M
        // drop's decimation 0.53 -> 0.47 s without them (medians of 3, an H100 host); the
        // 1.7M-particle frame's peak went from 154 to 161 MB (2 cores, PLY).)
        const size_t n = s.triangles.size();
        const bool countTarget = target.triangles > 0;
        const size_t needed = !countTarget           ? SIZE_MAX
                              : n > target.triangles ? (n - target.triangles + 1) / 2
                                                     : 0;
        if (needed == 0 || n == 0) break;

        const Blocks blocks = sortIntoBlocks(s, blockSide(s), pass % 2 ? 0.5 : 0.0);
        const util::NoInitVector<uint32_t>& tris = blocks.tris;
        const std::vector<size_t>& blockStart = blocks.start;
        const size_t nb = blockStart.size() - 1;

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
                        results[b].alive = blockStart[b + 1] - blockStart[b]; // as they are
                        continue;
                    }
                    Block block(s, &tris[blockStart[b]], blockStart[b + 1] - blockStart[b],
                                localOf.local());
                    results[b] = block.run(shares.threshold, target, budget[b]);
                }
            });
        // (valences lost by the vertices a block does not own: several blocks may take from
        // one, in any order, to the same count)
        tbb::parallel_for(size_t(0), nb, [&](size_t b) {
            for (const auto& [v, lost] : results[b].lost)
                __atomic_fetch_sub(&s.valence[v], lost, __ATOMIC_RELAXED);
        });
        size_t collapses = 0;
        for (size_t b = 0; b < nb; ++b) {
            const BlockResult& r = results[b];
            collapses += r.collapses;
            st.refused += r.refused;
            st.maxError = std::max(st.maxError, r.maxError);
            st.maxDrift = std::max(st.maxDrift, r.maxDrift);
            for (uint32_t v : r.touched)
                touched[v] = 1;
        }
        // The triangles left, in mesh order, moved down in place: each block wrote what it
        // kept over its first slots, and the rest are marked gone here. (Gathered in block
        // order into a new array, they took 21 MB more at the peak on the 1.7M-particle frame.)
        tbb::parallel_for(size_t(0), nb, [&](size_t b) {
            for (size_t i = blockStart[b] + results[b].alive; i < blockStart[b + 1]; ++i)
                s.refused[tris[i]] = kGone;
        });
        const size_t left = dropGone(s);
        s.triangles.resize(left);
        s.refused.resize(left);
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

    TriangleMesh out = compact(std::move(s), kept);
    if (stats) *stats = st; // no normals: see Normals.h
    return out;
}

} // namespace post
} // namespace fluidsurf
