// CellIndex.cc - Morton keys, parallel radix sort, cell ranges.
#include "neighbors/CellIndex.h"

#include "util/Floor.h"
#include "util/MarkedNumbers.h"
#include "util/Memory.h"
#include "util/Points4.h"
#include "util/RadixSort.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/ParticleSet.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <immintrin.h>

#include <algorithm>
#include <cmath>
#include <string>

namespace fluidsurf {
namespace neighbors {

namespace {

/// The thesis' "handler": cell key and particle id. Key: 32 bits where the grid's Morton keys
/// fit (up to 1024 cells an axis), else 64; the 8-byte handles halve what the sort moves (16
/// bytes with padding otherwise), and the sort was half of the index's time on the 13.1M drop.
template <typename Key> struct Handle
{
    Key key;
    uint32_t index;
};

/// The handles of particles [begin, end): each one's cell, clamped to the grid, and its key.
template <typename Key>
void cellKeys(const CellIndex& index, const Vec3f* positions, size_t begin, size_t end,
              Handle<Key>* handles)
{
    for (size_t i = begin; i != end; ++i) {
        uint32_t c[3];
        for (int a = 0; a < 3; ++a) {
            // (util::floorOf: std::floor is a libm call here; the quotient is within the grid,
            // far below floorOf's limit)
            const int64_t v =
                util::floorOf((double(positions[i][a]) - index.origin[a]) / index.cellSize);
            c[a] = uint32_t(std::clamp<int64_t>(v, 0, int64_t(index.dims[a]) - 1));
        }
        handles[i] = {Key(mortonKey(c[0], c[1], c[2])), uint32_t(i)};
    }
}

/// spreadBits on four 64-bit lanes.
__attribute__((target("avx2"))) inline __m256i spreadBits4(__m256i x)
{
    x = _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi64(x, 32)),
                         _mm256_set1_epi64x(0x1f00000000ffffll));
    x = _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi64(x, 16)),
                         _mm256_set1_epi64x(0x1f0000ff0000ffll));
    x = _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi64(x, 8)),
                         _mm256_set1_epi64x(0x100f00f00f00f00fll));
    x = _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi64(x, 4)),
                         _mm256_set1_epi64x(0x10c30c30c30c30c3ll));
    return _mm256_and_si256(_mm256_or_si256(x, _mm256_slli_epi64(x, 2)),
                            _mm256_set1_epi64x(0x1249249249249249ll));
}

/// cellKeys four particles at a time in AVX registers, where the CPU has AVX2: the same
/// subtraction and division in double, then floor, clamp and interleave on four lanes. The
/// same cells: the quotient's floor is exact either way, and so is the clamp of a whole
/// number below 2^21 (a NaN coordinate goes to cell 0 in both, as max(NaN, 0) gives 0; an
/// infinite one never gets here: its grid is rejected first). One particle at a time, this
/// was a quarter of the index's time on the 13.1M drop (three divisions and floors a particle,
/// with no SSE4.1 in the baseline build to floor in registers).
template <typename Key>
__attribute__((target("avx2"))) void cellKeysWide(const CellIndex& index, const Vec3f* positions,
                                                  size_t begin, size_t end, Handle<Key>* handles)
{
    __m256d origin[3], top[3];
    for (int a = 0; a < 3; ++a)
        origin[a] = _mm256_set1_pd(index.origin[a]), top[a] = _mm256_set1_pd(index.dims[a] - 1.0);
    const __m256d size = _mm256_set1_pd(index.cellSize), zero = _mm256_setzero_pd();
    size_t i = begin;
    for (; i + 4 <= end; i += 4) {
        __m128 xs, ys, zs;
        util::splitPoints4(&positions[i], xs, ys, zs);
        __m256i key = _mm256_setzero_si256();
        const __m128 axes[3] = {xs, ys, zs};
        for (int k = 0; k < 3; ++k) {
            const __m256d q =
                _mm256_div_pd(_mm256_sub_pd(_mm256_cvtps_pd(axes[k]), origin[k]), size);
            const __m256d cell = _mm256_min_pd(
                _mm256_max_pd(_mm256_round_pd(q, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC), zero),
                top[k]);
            const __m256i spread = spreadBits4(_mm256_cvtepu32_epi64(_mm256_cvttpd_epi32(cell)));
            key = _mm256_or_si256(key, _mm256_slli_epi64(spread, k));
        }
        alignas(32) uint64_t keys[4];
        _mm256_store_si256(reinterpret_cast<__m256i*>(keys), key);
        for (int l = 0; l < 4; ++l)
            handles[i + l] = {Key(keys[l]), uint32_t(i + l)};
    }
    cellKeys(index, positions, i, end, handles);
}

/// index's sorted particles and its cells (not the lookup) from positions, with keys of type
/// Key (index.origin, dims and cellSize set).
template <typename Key>
void sortIntoCells(CellIndex& index, const Vec3f* positions, const float* radii, size_t n,
                   Context& ctx)
{
    using H = Handle<Key>;
    std::vector<H, util::NoInitAllocator<H>> handles(n); // filled in parallel below
    static const bool wide = __builtin_cpu_supports("avx2");
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096),
                      [&](const tbb::blocked_range<size_t>& r) {
                          ctx.checkpoint();
                          (wide ? cellKeysWide<Key> : cellKeys<Key>)(index, positions, r.begin(),
                                                                     r.end(), handles.data());
                      });
    // by key, stably: the handles are in index order, so this is the sort by (key, index)
    int axisBits = 0;
    while (axisBits < 21 &&
           (uint64_t(1) << axisBits) < std::max({index.dims[0], index.dims[1], index.dims[2]}))
        ++axisBits;
    util::radixSortStable(handles, 3 * axisBits, [](const H& h) { return h.key; });

    index.positions.resize(n);
    index.order.resize(n);
    if (radii) index.radii.resize(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096),
                      [&](const tbb::blocked_range<size_t>& r) {
                          ctx.checkpoint();
                          for (size_t i = r.begin(); i != r.end(); ++i) {
                              const uint32_t src = handles[i].index;
                              index.order[i] = src;
                              index.positions[i] = positions[src];
                              if (radii) index.radii[i] = radii[src];
                          }
                      });
    // the occupied cells: where the key changes, numbered in order on all threads
    const util::MarkedNumbers cells(
        n, [&](size_t i) { return i == 0 || handles[i].key != handles[i - 1].key; });
    index.keys.resize(cells.count());
    index.starts.resize(cells.count() + 1);
    cells.forEach([&](size_t i, bool first, size_t k) {
        if (first) index.keys[k - 1] = handles[i].key, index.starts[k - 1] = uint32_t(i);
    });
    index.starts.back() = uint32_t(n);
}

} // namespace

void CellIndex::buildLookup()
{
    size_t size = 16;
    while (size < 2 * keys.size())
        size *= 2; // load factor <= 1/2
    const size_t mask = size - 1;
    tableKeys.resize(size);
    tableCells.resize(size);
    util::fillInParallel(tableKeys, kEmptyKey);
    // In parallel, each key claiming the first empty slot on from its own with a compare and
    // swap (as the device does): which slot a key gets then depends on the timing where keys
    // collide, but every key sits after no empty slot on its way, so find() finds the same
    // cell either way. (Serially, the inserts were an eighth of the index's time on 13.1M.)
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, keys.size(), 1 << 14),
        [&](const tbb::blocked_range<size_t>& r) {
            for (size_t c = r.begin(); c != r.end(); ++c)
                for (size_t slot = slotOfKey(keys[c], mask);; slot = (slot + 1) & mask) {
                    uint64_t empty = kEmptyKey;
                    if (__atomic_compare_exchange_n(&tableKeys[slot], &empty, keys[c], false,
                                                    __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
                        tableCells[slot] = uint32_t(c);
                        break;
                    }
                }
        });
}

void cellGrid(const BBox3f& box, double cellSize, double origin[3], uint32_t dims[3])
{
    for (int a = 0; a < 3; ++a) {
        // Cells counted from the one holding the lowest particle, so cellCoord's -1 sentinel
        // below the grid is never occupied.
        origin[a] = std::floor(double(box.min[a]) / cellSize) * cellSize;
        const double cells = std::floor((double(box.max[a]) - origin[a]) / cellSize) + 1;
        if (!(cells < double(kMaxCellsPerAxis)))
            throw ValueError("the particles span " + std::to_string(cells) + " cells of size " +
                             std::to_string(cellSize) + " along " + "xyz"[a] +
                             " (at most 2097152): a stray particle extremely far from the fluid?");
        dims[a] = uint32_t(cells);
    }
}

CellIndex buildCellIndex(const Vec3f* positions, const float* radii, size_t n, double cellSize,
                         Context& ctx)
{
    if (n >= (size_t(1) << 32) - 1) throw ValueError("more than 2^32 - 2 particles in one frame");
    if (!(cellSize > 0)) throw ValueError("cell size must be positive");
    CellIndex index;
    index.cellSize = cellSize;
    if (n == 0) {
        index.starts.push_back(0);
        return index;
    }
    const BBox3f box = boundsOf(positions, n);
    cellGrid(box, cellSize, index.origin, index.dims);
    // Morton keys interleave 3 axes: 32 bits hold 10 bits an axis
    if (std::max({index.dims[0], index.dims[1], index.dims[2]}) <= 1024)
        sortIntoCells<uint32_t>(index, positions, radii, n, ctx);
    else
        sortIntoCells<uint64_t>(index, positions, radii, n, ctx);
    index.buildLookup();
    return index;
}

void keepParticles(CellIndex& index, const std::vector<uint8_t>& keep)
{
    // Kept particles move down, in place (no second index). On all threads: each fixed chunk of
    // particles moves its kept ones down within its own range, in order (each written at or
    // before where it is read); those whose place lies in an earlier chunk's range wait, and
    // are written once every chunk has read its own (serially, 0.05 s for the 13.1M drop's 5
    // isolated particles). A chunk's waiting ones are at most the particles dropped before it,
    // so where many are dropped early, one thread moves them all instead.
    const bool radii = !index.radii.empty();
    const size_t n = index.size();
    const util::MarkedNumbers kept(n, [&](size_t i) { return keep[i] != 0; });
    const size_t dropped = n - kept.count();
    if (dropped == 0) return; // as it is
    struct Moved
    {
        size_t to;
        Vec3f position;
        uint32_t order;
        float radius;
    };
    auto move = [&](size_t from, size_t to) {
        index.positions[to] = index.positions[from];
        index.order[to] = index.order[from];
        if (radii) index.radii[to] = index.radii[from];
    };
    if (kept.chunks() * dropped <= n / 16) {
        std::vector<std::vector<Moved>> waiting(kept.chunks());
        kept.forEachChunk([&](size_t c, size_t begin, size_t end, size_t before) {
            size_t to = before;
            for (size_t i = begin; i < end; ++i) {
                if (!keep[i]) continue;
                if (to >= begin)
                    move(i, to);
                else
                    waiting[c].push_back(
                        {to, index.positions[i], index.order[i], radii ? index.radii[i] : 0.f});
                ++to;
            }
        });
        tbb::parallel_for(size_t(0), waiting.size(), [&](size_t c) {
            for (const Moved& m : waiting[c]) {
                index.positions[m.to] = m.position, index.order[m.to] = m.order;
                if (radii) index.radii[m.to] = m.radius;
            }
        });
    } else {
        size_t to = 0;
        for (size_t i = 0; i < n; ++i)
            if (keep[i]) move(i, to++);
    }
    // the cells: each starts where its first kept particle went; empty ones go (their kept
    // particles counted on all threads, the cells, an eighth as many, moved by one)
    util::NoInitVector<uint32_t> here(index.keys.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, here.size()),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t c = r.begin(); c != r.end(); ++c) {
                              uint32_t k = 0;
                              for (uint32_t i = index.starts[c]; i < index.starts[c + 1]; ++i)
                                  k += keep[i] != 0;
                              here[c] = k;
                          }
                      });
    size_t at = 0, cells = 0; // kept particles before cell c
    for (size_t c = 0; c < index.keys.size(); ++c) {
        if (here[c] > 0) index.keys[cells] = index.keys[c], index.starts[cells++] = uint32_t(at);
        at += here[c];
    }
    index.positions.resize(kept.count()), index.order.resize(kept.count());
    if (radii) index.radii.resize(kept.count());
    index.keys.resize(cells), index.starts.resize(cells);
    index.starts.push_back(uint32_t(kept.count()));
    index.buildLookup();
}

} // namespace neighbors
} // namespace fluidsurf
