// SpacingEstimate.cc - nearest neighbours through the pipeline's own cell index
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

namespace fluidsurf {

namespace {
constexpr int kMaxShell = 8;
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

    Context ctx; // (a fraction of a second: no progress to report)
    const neighbors::CellIndex index =
        neighbors::buildCellIndex(ps.positions.data(), nullptr, n, cell, ctx);

    // the samples: particle q = floor(s n / samples) for s < samples (all if fewer), found by
    // their place in the index's order
    const size_t samples = std::min(n, maxSamples);
    std::vector<double> nearest(samples, -1.0);
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, n, 4096), [&](const tbb::blocked_range<size_t>& r) {
            for (size_t t = r.begin(); t != r.end(); ++t) {
                const size_t q = index.order[t];
                // the smallest s with floor(s n / samples) >= q; q is sampled if it lands on q
                const size_t s = size_t(((unsigned __int128)q * samples + n - 1) / n);
                if (s >= samples || size_t((unsigned __int128)s * n / samples) != q) continue;
                const Vec3f& p = index.positions[t];
                const int64_t ci = index.cellCoord(p.x, 0), cj = index.cellCoord(p.y, 1),
                              ck = index.cellCoord(p.z, 2);
                double best = INFINITY;
                for (int shell = 0; shell <= kMaxShell; ++shell) {
                    for (int di = -shell; di <= shell; ++di)
                        for (int dj = -shell; dj <= shell; ++dj)
                            for (int dk = -shell; dk <= shell; ++dk) {
                                if (std::max({std::abs(di), std::abs(dj), std::abs(dk)}) != shell)
                                    continue;
                                const neighbors::CellRange range =
                                    index.find(ci + di, cj + dj, ck + dk);
                                for (uint32_t u = range.begin; u < range.end; ++u) {
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
    std::nth_element(found.begin(), found.begin() + found.size() / 2, found.end());
    est.medianNearest = found[found.size() / 2];
    est.radius = est.medianNearest / 2;
    return est;
}

} // namespace fluidsurf
