// SpacingEstimate.cc - nearest neighbours and densities through the pipeline's own cell index
// (neighbors/CellIndex: particles sorted into cells in Z-order, a hash table of the occupied
// ones). The cell size comes from the bounding-box volume per particle; each query searches
// shells of cells outwards until the best distance found is closer than any unvisited shell
// (exact), or gives up after a fixed number of shells (an isolated particle). The queries run
// in the index's order, so neighbouring queries share their cells in the cache (0.36 -> 0.27 s
// for `info` on the 1.7M-particle frame, 2 cores, against a std::unordered_map of cells and
// queries in file order). Memory is proportional to the particle count.
#include <fluidsurf/SpacingEstimate.h>

#include "neighbors/CellIndex.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>
#include <vector>

namespace fluidsurf {

namespace {
constexpr int kMaxShell = 8;
/// Particles whose density is summed (evenly spread in the index's order): the quantile of a
/// few thousand densities is as good as that of all of them.
constexpr size_t kDensitySamples = 20000;
/// The density kernel's support, in spacings: 2.5 puts the poly6 sum on a cubic lattice within
/// 0.5% of one particle per spacing cubed (0.15% in spacing), with about 65 particles in reach.
constexpr double kSupport = 2.5;
/// The bulk's density: the median of the sampled densities within this share of the top
/// tenth's (surface particles have fewer neighbours, and a quarter or more of a frame's
/// particles lie near its surface).
constexpr double kBulk = 0.9;
/// A frame whose top tenth has fewer particles in reach than this (of about 65 in a full
/// neighbourhood) has no bulk whose density could be the rest density: scattered or random
/// points, a shell, a thin sheet. Its nearest-neighbour spacing stands.
constexpr uint32_t kMinBulkNeighbours = 40;
/// Particles of one cell that a query visits at most: an even sample of a fuller cell, each
/// standing for `step` of them (see SpacingEstimate.h). Cells are about a spacing wide, so real
/// frames hold a few particles a cell.
constexpr uint32_t kCellVisits = 2048;

/// The stride through a cell's range that visits at most kCellVisits of its particles (the
/// density sums, an estimate: a fuller cell's particles evenly sampled, each standing for
/// stride of them).
inline uint32_t strideOf(const neighbors::CellRange& range)
{
    const uint32_t n = range.end - range.begin;
    return n > kCellVisits ? (n + kCellVisits - 1) / kCellVisits : 1;
}

/// A cell too full to scan whole for each query (a pile of coincident or near-coincident
/// particles, or cells made huge by a far outlier: 200,000 particles at one point took minutes):
/// its particles sorted along its widest axis, so that a nearest-neighbour query scans outwards
/// from its own place and stops where that axis alone puts the rest past the best distance, or
/// at a distance of 0. Exact, as the plain scan.
struct SortedCell
{
    int axis = 0;
    std::vector<float> keys;     ///< the positions along axis, ascending
    std::vector<uint32_t> order; ///< the particles (index order) in that order
};

/// Every cell holding more than kCellVisits particles, sorted (by its range's begin).
std::unordered_map<uint32_t, SortedCell> sortFullCells(const neighbors::CellIndex& index,
                                                       Context& ctx)
{
    std::vector<neighbors::CellRange> full;
    for (uint32_t t = 0; t < uint32_t(index.size());) {
        const Vec3f& p = index.positions[t];
        const neighbors::CellRange r =
            index.find(index.cellCoord(p.x, 0), index.cellCoord(p.y, 1), index.cellCoord(p.z, 2));
        if (r.end <= t || r.begin > t) { // (not where the index puts it: cannot happen)
            ++t;
            continue;
        }
        if (r.end - r.begin > kCellVisits) full.push_back(r);
        t = r.end;
    }
    std::vector<SortedCell> sorted(full.size());
    tbb::parallel_for(size_t(0), full.size(), [&](size_t c) {
        ctx.checkpoint();
        const neighbors::CellRange r = full[c];
        BBox3f box;
        for (uint32_t u = r.begin; u < r.end; ++u)
            box.expand(index.positions[u]);
        SortedCell& s = sorted[c];
        for (int a = 1; a < 3; ++a)
            if (box.max[a] - box.min[a] > box.max[s.axis] - box.min[s.axis]) s.axis = a;
        for (uint32_t u = r.begin; u < r.end; ++u)
            s.order.push_back(u);
        std::sort(s.order.begin(), s.order.end(), [&](uint32_t a, uint32_t b) {
            return index.positions[a][s.axis] < index.positions[b][s.axis] ||
                   (index.positions[a][s.axis] == index.positions[b][s.axis] && a < b);
        });
        for (uint32_t u : s.order)
            s.keys.push_back(index.positions[u][s.axis]);
    });
    std::unordered_map<uint32_t, SortedCell> byBegin;
    for (size_t c = 0; c < full.size(); ++c)
        byBegin.emplace(full[c].begin, std::move(sorted[c]));
    return byBegin;
}

/// best = min(best, squared distance from p (particle self) to the cell's particles), scanning
/// outwards from p's place along the cell's axis (see SortedCell).
void nearestInSortedCell(const neighbors::CellIndex& index, const SortedCell& cell, const Vec3f& p,
                         uint32_t self, double& best)
{
    const double key = p[cell.axis];
    const size_t mid = size_t(std::lower_bound(cell.keys.begin(), cell.keys.end(), float(key)) -
                              cell.keys.begin());
    auto visit = [&](size_t i) {
        const uint32_t u = cell.order[i];
        if (u == self) return;
        const Vec3f& o = index.positions[u];
        const double dx = double(o.x) - p.x, dy = double(o.y) - p.y, dz = double(o.z) - p.z;
        best = std::min(best, dx * dx + dy * dy + dz * dz);
    };
    for (size_t i = mid; i < cell.keys.size() && best > 0; ++i) {
        const double d = double(cell.keys[i]) - key;
        if (d * d > best) break;
        visit(i);
    }
    for (size_t i = mid; i-- > 0 && best > 0;) {
        const double d = key - double(cell.keys[i]);
        if (d * d > best) break;
        visit(i);
    }
}

/// Nearest-neighbour distances this close to each other (the middle half within this share of
/// their median) mark ordered particles: a lattice, whose nearest distance is its spacing.
constexpr double kOrdered = 0.01;

/// Per axis a and offset d with |d| = shell, gap2[a * (2 reach + 1) + d + reach]: the square of
/// the gap between p and the slab of cells c[a] + d, less a margin for the rounding of the cell
/// coordinates and of the distances. No particle of a cell lies closer to p than the sum of its
/// three axes' values.
void axisGaps(const neighbors::CellIndex& index, const Vec3f& p, int64_t ci, int64_t cj, int64_t ck,
              int shell, int reach, double* gap2)
{
    const double cell = index.cellSize;
    const int64_t c[3] = {ci, cj, ck};
    const double at[3] = {p.x, p.y, p.z};
    const size_t width = size_t(2 * reach + 1);
    for (int a = 0; a < 3; ++a)
        for (int d : {-shell, shell}) {
            const double low = index.origin[a] + double(c[a] + d) * cell,
                         margin = 1e-6 * cell + 1e-12 * std::abs(at[a]);
            const double g = std::max({0.0, low - at[a], at[a] - (low + cell)});
            gap2[a * width + size_t(d + reach)] = g > margin ? (g - margin) * (g - margin) : 0;
        }
}

/// Every axis' gaps for the offsets in [-reach, reach] (see axisGaps).
void axisGapsWithin(const neighbors::CellIndex& index, const Vec3f& p, int64_t ci, int64_t cj,
                    int64_t ck, int reach, double* gap2)
{
    for (int shell = 0; shell <= reach; ++shell)
        axisGaps(index, p, ci, cj, ck, shell, reach, gap2);
}

/// The rest spacing the particles' SPH density implies: one particle per spacing cubed. Each
/// sampled particle sums a poly6 kernel (support kSupport spacings) over the particles in its
/// reach, itself included (see kBulk for the bulk's); two rounds from `start`, each with the
/// support of the spacing the last one found. 0 where there is no bulk (kMinBulkNeighbours).
double densitySpacing(const neighbors::CellIndex& index, double cell, double start, Context& ctx)
{
    const size_t n = index.size(), samples = std::min(n, kDensitySamples);
    double spacing = start;
    for (int round = 0; round < 2 && spacing > 0; ++round) {
        const double support = kSupport * spacing, support2 = support * support;
        const double norm = 315.0 / (64.0 * M_PI * std::pow(support, 9));
        const int reach = int(std::ceil(support / cell));
        const size_t width = size_t(2 * reach + 1);
        std::vector<double> density(samples);
        std::vector<uint32_t> count(samples);
        tbb::parallel_for(
            tbb::blocked_range<size_t>(0, samples, 256), [&](const tbb::blocked_range<size_t>& r) {
                ctx.checkpoint();
                std::vector<double> gap2(3 * width);
                for (size_t s = r.begin(); s != r.end(); ++s) {
                    const Vec3f& p = index.positions[s * n / samples];
                    const int64_t ci = index.cellCoord(p.x, 0), cj = index.cellCoord(p.y, 1),
                                  ck = index.cellCoord(p.z, 2);
                    // a cell beyond the support by its gap holds nothing that adds to the sums,
                    // so it is not looked up (half of them, and the look-ups were most of the
                    // estimate's time on small frames)
                    axisGapsWithin(index, p, ci, cj, ck, reach, gap2.data());
                    double sum = 0;
                    count[s] = 0;
                    for (int di = -reach; di <= reach; ++di)
                        for (int dj = -reach; dj <= reach; ++dj)
                            for (int dk = -reach; dk <= reach; ++dk) {
                                if (gap2[size_t(di + reach)] + gap2[width + size_t(dj + reach)] +
                                        gap2[2 * width + size_t(dk + reach)] >
                                    support2)
                                    continue;
                                const neighbors::CellRange range =
                                    index.find(ci + di, cj + dj, ck + dk);
                                const uint32_t step = strideOf(range);
                                for (uint32_t u = range.begin; u < range.end; u += step) {
                                    const Vec3f& o = index.positions[u];
                                    const double dx = double(o.x) - p.x, dy = double(o.y) - p.y,
                                                 dz = double(o.z) - p.z;
                                    const double t = support2 - (dx * dx + dy * dy + dz * dz);
                                    if (t > 0) sum += step * t * t * t, count[s] += step;
                                }
                            }
                    density[s] = sum * norm;
                }
            });
        // the bulk: the densities within kBulk of the top tenth's lowest; their median
        // (by selection, as a sort would place them: the 90% quantile, then the middle of the
        // densities from kBulk of it up)
        const auto at = [&](size_t k) { return density.begin() + ptrdiff_t(k); };
        const size_t tenth = size_t(0.9 * double(samples - 1));
        std::nth_element(density.begin(), at(tenth), density.end());
        const double top = density[tenth];
        const size_t bulk = size_t(std::count_if(density.begin(), density.end(),
                                                 [&](double d) { return d >= kBulk * top; }));
        const size_t middle = samples - bulk + bulk / 2;
        std::nth_element(density.begin(), at(middle), density.end());
        const double value = density[middle];
        spacing = value > 0 ? std::pow(value, -1.0 / 3) : 0;
        if (!std::isfinite(spacing)) spacing = 0;
        if (round == 1) { // (in the last round, whose support is the spacing's)
            const auto tenth = count.begin() + ptrdiff_t(samples * 9 / 10);
            std::nth_element(count.begin(), tenth, count.end());
            if (*tenth < kMinBulkNeighbours) return 0; // no bulk
        }
    }
    return spacing;
}
} // namespace

SpacingEstimate estimateSpacing(const ParticleSet& ps, size_t maxSamples)
{
    Context ctx; // (a fraction of a second: no progress to report)
    return estimateSpacing(ps, ctx, maxSamples);
}

SpacingEstimate estimateSpacing(const ParticleSet& ps, Context& ctx, size_t maxSamples)
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

    const neighbors::CellIndex index =
        neighbors::buildCellIndex(ps.positions.data(), nullptr, n, cell, ctx);

    // the samples: particle q = floor(s n / samples) for s < samples (all if fewer), found by
    // their place in the index's order
    const size_t samples = std::min(n, maxSamples);
    std::vector<double> nearest(samples, -1.0);
    // the sampled particles marked (q = floor(s n / samples) for sample s; one bit a particle):
    // the loop below runs over all of them in the index's order, and two 128-bit divisions per
    // particle to tell whether it is sampled took 8-10 ms of one thread on the 1.7M-particle
    // frame, where marking takes 0.6 ms (the products fit in 64 bits: buildCellIndex takes
    // fewer than 2^32 particles)
    std::vector<uint64_t> isSampled((n + 63) / 64, 0);
    for (size_t s = 0; s < samples; ++s) {
        const uint64_t q = uint64_t(s) * n / samples;
        isSampled[q / 64] |= uint64_t(1) << (q % 64);
    }
    const std::unordered_map<uint32_t, SortedCell> fullCells = sortFullCells(index, ctx);
    constexpr int kWidth = 2 * kMaxShell + 1;
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
            ctx.checkpoint();
            double gap2[3 * kWidth];
            for (size_t t = r.begin(); t != r.end(); ++t) {
                const size_t q = index.order[t];
                if (!(isSampled[q / 64] >> (q % 64) & 1)) continue;
                // q's sample: the smallest s with floor(s n / samples) >= q
                const size_t s = size_t((uint64_t(q) * samples + n - 1) / n);
                const Vec3f& p = index.positions[t];
                const int64_t ci = index.cellCoord(p.x, 0), cj = index.cellCoord(p.y, 1),
                              ck = index.cellCoord(p.z, 2);
                double best = INFINITY;
                for (int shell = 0; shell <= kMaxShell; ++shell) {
                    axisGaps(index, p, ci, cj, ck, shell, kMaxShell, gap2);
                    for (int di = -shell; di <= shell; ++di)
                        for (int dj = -shell; dj <= shell; ++dj)
                            for (int dk = -shell; dk <= shell; ++dk) {
                                if (std::max({std::abs(di), std::abs(dj), std::abs(dk)}) != shell)
                                    continue;
                                // a cell whose nearest point lies farther than the best so far
                                // cannot hold the nearest particle (the minimum is the same
                                // whichever cells are passed over; most of the 26 around p)
                                if (gap2[di + kMaxShell] + gap2[kWidth + dj + kMaxShell] +
                                        gap2[2 * kWidth + dk + kMaxShell] >
                                    best)
                                    continue;
                                const neighbors::CellRange range =
                                    index.find(ci + di, cj + dj, ck + dk);
                                if (range.end - range.begin > kCellVisits) {
                                    nearestInSortedCell(index, fullCells.at(range.begin), p,
                                                        uint32_t(t), best);
                                    continue;
                                }
                                for (uint32_t u = range.begin; u < range.end && best > 0; ++u) {
                                    if (u == t) continue;
                                    const Vec3f& o = index.positions[u];
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
    // three order statistics, each selected in what lies on its side of the one before (the
    // same values as a sort's, in linear time: the sort was a fifth of the searches' time)
    const auto at = [&](size_t k) { return found.begin() + ptrdiff_t(k); };
    const size_t half = found.size() / 2, low = found.size() / 4, high = 3 * found.size() / 4;
    std::nth_element(found.begin(), at(half), found.end());
    est.medianNearest = found[half];
    if (low < half) std::nth_element(found.begin(), at(low), at(half));
    if (high > half) std::nth_element(at(half + 1), at(high), found.end());
    est.spacing = est.medianNearest;
    // Ordered particles (a lattice) and flat layers: the nearest distance is the spacing.
    // Disordered SPH particles pair up, their nearest distance 0.72-0.85 of the rest spacing
    // on the DualSPHysics frames (../shared/data/README.md) and 0.72-0.95 on SPlisHSPlasH's:
    // there the density, which the simulator holds at its rest value, gives the spacing.
    const double quarter = found[low], threeQuarters = found[high];
    const bool ordered = threeQuarters - quarter <= kOrdered * est.medianNearest;
    if (dims == 3 && !ordered) {
        const double fromDensity = densitySpacing(index, cell, est.medianNearest, ctx);
        if (fromDensity > 0) est.spacing = fromDensity, est.fromDensity = true;
    }
    est.radius = est.spacing / 2;
    return est;
}

} // namespace fluidsurf
