// SpacingEstimate.cc - nearest neighbours through a hashed uniform grid. The cell size comes from
// the bounding-box volume per particle; each query searches shells of cells outwards until the
// best distance found is closer than any unvisited shell (exact), or gives up after a fixed
// number of shells (an isolated particle). Memory is proportional to the particle count.
//
// What made it fast (0.3 s -> 0.1 s on the 1.7M-particle frame, 2 cores, the same estimate):
// the cells are a flat open-addressing table (std::unordered_map's divisions and pointer chases
// were half the time), the particles are copied in cell order (a cell's are then one or two
// cache lines, not one line each), the queries run in cell order (neighbouring queries share
// their cells in the cache), and the keys are sorted by a radix sort on their few bits.
#include <fluidsurf/SpacingEstimate.h>

#include "neighbors/CellIndex.h" // slotOfKey
#include "util/Memory.h"
#include "util/RadixSort.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace fluidsurf {

namespace {
constexpr int kMaxShell = 8;
constexpr uint64_t kEmpty = ~uint64_t(0);

struct Keyed
{
    uint64_t key;   ///< the cell, i | j << bits[0] | k << (bits[0] + bits[1])
    uint32_t index; ///< the particle
};

int bitsFor(int64_t cells)
{
    int b = 0;
    while ((int64_t(1) << b) < cells)
        ++b;
    return b;
}
} // namespace

SpacingEstimate estimateSpacing(const ParticleSet& ps, size_t maxSamples)
{
    SpacingEstimate est;
    const size_t n = ps.size();
    if (n < 2) return est;
    const BBox3f box = ps.bbox();
    double ext[3];
    for (int a = 0; a < 3; ++a)
        ext[a] = double(box.max[a]) - double(box.min[a]);
    // Volume per particle, ignoring flat axes (a single layer of particles).
    const double maxExt = std::max({ext[0], ext[1], ext[2]});
    if (!(maxExt > 0)) return est;
    int dims = 0;
    double vol = 1;
    for (double e : ext)
        if (e > 1e-6 * maxExt) {
            vol *= e;
            ++dims;
        }
    double cell = std::pow(vol / double(n), 1.0 / std::max(dims, 1));
    if (!(cell > 0) || !std::isfinite(cell)) cell = maxExt;
    cell = std::max(cell, maxExt * 1e-6);

    // cells per axis, and their bits in a key: at most 1e6 + 1 per axis (cell >= 1e-6 of the
    // largest extent), 60 bits in all
    int64_t cells[3];
    int bits[3];
    for (int a = 0; a < 3; ++a)
        cells[a] = int64_t(std::floor((double(box.max[a]) - double(box.min[a])) / cell)) + 1,
        bits[a] = bitsFor(cells[a]);
    // (clamped: a non-finite point, which the bounds leave out, stays within its key's bits)
    auto coord = [&](float v, int a) {
        const double c = std::floor((double(v) - double(box.min[a])) / cell);
        return c >= 0 ? std::min(int64_t(std::min(c, 4e6)), cells[a] - 1) : int64_t(0);
    };
    auto keyOf = [&](int64_t i, int64_t j, int64_t k) {
        return uint64_t(i) | uint64_t(j) << bits[0] | uint64_t(k) << (bits[0] + bits[1]);
    };
    std::vector<Keyed, util::NoInitAllocator<Keyed>> keyed(n);
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                const Vec3f& p = ps.positions[i];
                keyed[i] = {keyOf(coord(p.x, 0), coord(p.y, 1), coord(p.z, 2)), uint32_t(i)};
            }
        });
    util::radixSortStable(keyed, bits[0] + bits[1] + bits[2], [](const Keyed& k) { return k.key; });
    // the particles in cell order, and the occupied cells: key -> [begin, end) in that order
    std::vector<Vec3f, util::NoInitAllocator<Vec3f>> sorted(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t t = r.begin(); t != r.end(); ++t)
                              sorted[t] = ps.positions[keyed[t].index];
                      });
    std::vector<uint32_t> starts; // of each occupied cell, in key order, and n
    for (size_t t = 0; t < n; ++t)
        if (t == 0 || keyed[t].key != keyed[t - 1].key) starts.push_back(uint32_t(t));
    starts.push_back(uint32_t(n));
    size_t size = 16;
    while (size < 2 * starts.size())
        size *= 2; // load factor <= 1/2
    const size_t mask = size - 1;
    std::vector<uint64_t> tableKeys(size, kEmpty);
    std::vector<uint32_t> tableCells(size);
    for (uint32_t c = 0; c + 1 < starts.size(); ++c) {
        const uint64_t key = keyed[starts[c]].key;
        size_t slot = neighbors::slotOfKey(key, mask);
        while (tableKeys[slot] != kEmpty)
            slot = (slot + 1) & mask;
        tableKeys[slot] = key, tableCells[slot] = c;
    }
    auto find = [&](int64_t i, int64_t j, int64_t k, uint32_t& b, uint32_t& e) {
        if (i < 0 || j < 0 || k < 0 || i >= cells[0] || j >= cells[1] || k >= cells[2])
            return false;
        const uint64_t key = keyOf(i, j, k);
        for (size_t slot = neighbors::slotOfKey(key, mask);; slot = (slot + 1) & mask) {
            if (tableKeys[slot] == key) {
                b = starts[tableCells[slot]], e = starts[tableCells[slot] + 1];
                return true;
            }
            if (tableKeys[slot] == kEmpty) return false;
        }
    };

    // the samples: particle q = floor(s n / samples) for s < samples (all if fewer), found by
    // their place in cell order
    const size_t samples = std::min(n, maxSamples);
    std::vector<double> nearest(samples, -1.0);
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t t = r.begin(); t != r.end(); ++t) {
                const size_t q = keyed[t].index;
                // the smallest s with floor(s n / samples) >= q; q is sampled if it lands on q
                const size_t s = size_t(((unsigned __int128)q * samples + n - 1) / n);
                if (s >= samples || size_t((unsigned __int128)s * n / samples) != q) continue;
                const Vec3f& p = sorted[t];
                const int64_t ci = coord(p.x, 0), cj = coord(p.y, 1), ck = coord(p.z, 2);
                double best = INFINITY;
                for (int shell = 0; shell <= kMaxShell; ++shell) {
                    for (int di = -shell; di <= shell; ++di)
                        for (int dj = -shell; dj <= shell; ++dj)
                            for (int dk = -shell; dk <= shell; ++dk) {
                                if (std::max({std::abs(di), std::abs(dj), std::abs(dk)}) != shell)
                                    continue;
                                uint32_t b, e;
                                if (!find(ci + di, cj + dj, ck + dk, b, e)) continue;
                                for (uint32_t u = b; u < e; ++u) {
                                    if (u == t) continue;
                                    const Vec3f& o = sorted[u];
                                    const double dx = double(o.x) - p.x, dy = double(o.y) - p.y,
                                                 dz = double(o.z) - p.z;
                                    const double d2 = dx * dx + dy * dy + dz * dz;
                                    if (d2 < best) best = d2;
                                }
                            }
                    // Every unvisited point lies at least shell * cell away.
                    if (best <= (shell * cell) * (shell * cell)) break;
                }
                nearest[s] = std::isfinite(best) ? std::sqrt(best) : -1.0;
            }
        });
    std::vector<double> found;
    found.reserve(samples);
    for (double d : nearest)
        if (d >= 0) found.push_back(d);
    est.sampled = samples;
    est.isolated = samples - found.size();
    if (found.empty()) return est;
    std::nth_element(found.begin(), found.begin() + found.size() / 2, found.end());
    est.medianNearest = found[found.size() / 2];
    est.radius = est.medianNearest / 2;
    return est;
}

} // namespace fluidsurf
