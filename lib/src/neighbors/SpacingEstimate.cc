// SpacingEstimate.cc - nearest neighbours through a hashed uniform grid. The cell size comes from
// the bounding-box volume per particle; each query searches shells of cells outwards until the
// best distance found is closer than any unvisited shell (exact), or gives up after a fixed
// number of shells (an isolated particle). Memory is proportional to the particle count.
#include <fluidsurf/SpacingEstimate.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <unordered_map>

namespace fluidsurf {

namespace {
constexpr int kMaxShell = 8;

struct CellKey
{
    static uint64_t of(int64_t i, int64_t j, int64_t k)
    {
        const uint64_t m = (uint64_t(1) << 21) - 1; // 21 bits per axis, wraps harmlessly
        return (uint64_t(i) & m) | ((uint64_t(j) & m) << 21) | ((uint64_t(k) & m) << 42);
    }
};
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

    auto coord = [&](float v, int a) {
        return int64_t(std::floor((double(v) - double(box.min[a])) / cell));
    };
    std::vector<std::pair<uint64_t, uint32_t>> keyed(n);
    tbb::parallel_for(size_t(0), n, [&](size_t i) {
        const Vec3f& p = ps.positions[i];
        keyed[i] = {CellKey::of(coord(p.x, 0), coord(p.y, 1), coord(p.z, 2)), uint32_t(i)};
    });
    tbb::parallel_sort(keyed.begin(), keyed.end());
    std::unordered_map<uint64_t, std::pair<uint32_t, uint32_t>> ranges;
    for (size_t s = 0; s < n;) {
        size_t e = s;
        while (e < n && keyed[e].first == keyed[s].first)
            ++e;
        ranges.emplace(keyed[s].first, std::make_pair(uint32_t(s), uint32_t(e)));
        s = e;
    }

    const size_t samples = std::min(n, maxSamples);
    std::vector<double> nearest(samples, -1.0);
    tbb::parallel_for(size_t(0), samples, [&](size_t s) {
        const size_t q = samples == n ? s : size_t((unsigned __int128)(s)*n / samples);
        const Vec3f& p = ps.positions[q];
        const int64_t ci = coord(p.x, 0), cj = coord(p.y, 1), ck = coord(p.z, 2);
        double best = INFINITY;
        for (int shell = 0; shell <= kMaxShell; ++shell) {
            for (int di = -shell; di <= shell; ++di)
                for (int dj = -shell; dj <= shell; ++dj)
                    for (int dk = -shell; dk <= shell; ++dk) {
                        if (std::max({std::abs(di), std::abs(dj), std::abs(dk)}) != shell) continue;
                        auto it = ranges.find(CellKey::of(ci + di, cj + dj, ck + dk));
                        if (it == ranges.end()) continue;
                        for (uint32_t t = it->second.first; t < it->second.second; ++t) {
                            const uint32_t j = keyed[t].second;
                            if (j == q) continue;
                            const Vec3f& o = ps.positions[j];
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
