// MeshDistance.cc - one side of the Hausdorff distance between meshes (see MeshCheck.h): exact
// point-to-triangle distances, the candidate triangles from a sorted table of (cell, triangle)
// for cells of about an edge, searched ring by ring out from the point until nothing nearer can
// be left; the points in parallel (the maximum is the same in any order).
#include <fluidsurf/MeshCheck.h>

#include "util/TriangleDistance.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>
#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <limits>

namespace fluidsurf {

namespace {

class Buckets
{
public:
    Buckets(const TriangleMesh& mesh, double cell) : mMesh(mesh), mCell(cell)
    {
        std::vector<size_t> first(mesh.triangles.size() + 1, 0);
        auto range = [&](uint32_t t, int64_t lo[3], int64_t hi[3]) {
            for (int k = 0; k < 3; ++k) {
                double a = std::numeric_limits<double>::max(), b = -a;
                for (uint32_t v : mesh.triangles[t])
                    a = std::min(a, double(mesh.points[v][k])),
                    b = std::max(b, double(mesh.points[v][k]));
                lo[k] = index(a), hi[k] = index(b);
            }
        };
        for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
            int64_t lo[3], hi[3];
            range(t, lo, hi);
            first[t + 1] =
                first[t] + size_t((hi[0] - lo[0] + 1) * (hi[1] - lo[1] + 1) * (hi[2] - lo[2] + 1));
        }
        mEntries.resize(first.back());
        tbb::parallel_for(tbb::blocked_range<uint32_t>(0, uint32_t(mesh.triangles.size())),
                          [&](const tbb::blocked_range<uint32_t>& r) {
                              for (uint32_t t = r.begin(); t != r.end(); ++t) {
                                  int64_t lo[3], hi[3];
                                  range(t, lo, hi);
                                  size_t i = first[t];
                                  for (int64_t x = lo[0]; x <= hi[0]; ++x)
                                      for (int64_t y = lo[1]; y <= hi[1]; ++y)
                                          for (int64_t z = lo[2]; z <= hi[2]; ++z)
                                              mEntries[i++] = {key(x, y, z), t};
                              }
                          });
        tbb::parallel_sort(mEntries.begin(), mEntries.end());
    }

    /// Distance from p to the mesh, or +inf beyond `reach`: the cells in rings around p's cell,
    /// nearest ring first, until no unvisited cell can hold anything nearer (a cell k rings out
    /// is at least (k - 1) cells away). Some distance <= `enough` as soon as one is found: the
    /// caller wants the largest distance, and a point this near cannot be it.
    double operator()(const Vec3d& p, double reach, double enough) const
    {
        double best = std::numeric_limits<double>::infinity();
        const int64_t c[3] = {index(p[0]), index(p[1]), index(p[2])};
        const int64_t rings = int64_t(std::ceil(reach / mCell)) + 1;
        for (int64_t k = 0; k <= rings && !(best <= double(k - 1) * mCell); ++k)
            for (int64_t x = c[0] - k; x <= c[0] + k; ++x)
                for (int64_t y = c[1] - k; y <= c[1] + k; ++y) {
                    const bool side = std::abs(x - c[0]) == k || std::abs(y - c[1]) == k;
                    for (int64_t z = c[2] - k; z <= c[2] + k;
                         z += side ? 1 : 2 * std::max<int64_t>(k, 1)) {
                        visit(p, key(x, y, z), best);
                        if (best <= enough) return best;
                    }
                }
        return best <= reach ? best : std::numeric_limits<double>::infinity();
    }

private:
    void visit(const Vec3d& p, uint64_t k, double& best) const
    {
        auto it =
            std::lower_bound(mEntries.begin(), mEntries.end(), std::pair<uint64_t, uint32_t>(k, 0));
        for (; it != mEntries.end() && it->first == k; ++it) {
            const auto& tri = mMesh.triangles[it->second];
            best = std::min(best, triangleDistance(p, toVec3d(mMesh.points[tri[0]]),
                                                   toVec3d(mMesh.points[tri[1]]),
                                                   toVec3d(mMesh.points[tri[2]])));
        }
    }

    int64_t index(double v) const { return int64_t(std::floor(v / mCell)); }
    static uint64_t key(int64_t x, int64_t y, int64_t z)
    {
        return (uint64_t(x & 0x1fffff) << 42) | (uint64_t(y & 0x1fffff) << 21) |
               uint64_t(z & 0x1fffff);
    }
    const TriangleMesh& mMesh;
    double mCell;
    std::vector<std::pair<uint64_t, uint32_t>> mEntries; ///< (cell, triangle), sorted
};

} // namespace

namespace {

/// Buckets of b's triangles, in cells of about its mean edge (a point's nearest triangles are
/// then a ring or two away).
Buckets bucketsOf(const TriangleMesh& b, double reach)
{
    double edges = 0;
    for (const auto& t : b.triangles)
        edges += (toVec3d(b.points[t[1]]) - toVec3d(b.points[t[0]])).length();
    return Buckets(b, std::clamp(edges / double(b.triangles.size()), reach / 16, reach));
}

/// The sample points of a: its used vertices (np of them, i < np), then its triangles' middles.
bool samplePoint(const TriangleMesh& a, const std::vector<uint8_t>& used, size_t i, Vec3d& p)
{
    const size_t np = a.points.size();
    if (i < np) {
        if (!used[i]) return false;
        p = toVec3d(a.points[i]);
        return true;
    }
    const auto& tri = a.triangles[i - np];
    p = (toVec3d(a.points[tri[0]]) + toVec3d(a.points[tri[1]]) + toVec3d(a.points[tri[2]])) / 3.0;
    return true;
}

std::vector<uint8_t> usedPoints(const TriangleMesh& a)
{
    std::vector<uint8_t> used(a.points.size(), 0);
    for (const auto& t : a.triangles)
        used[t[0]] = used[t[1]] = used[t[2]] = 1;
    return used;
}

} // namespace

double meanMeshDistance(const TriangleMesh& a, const TriangleMesh& b, double reach)
{
    if (a.triangles.empty()) return 0;
    if (b.triangles.empty() || !(reach > 0)) return reach > 0 ? reach : 0;
    const Buckets buckets = bucketsOf(b, reach);
    const std::vector<uint8_t> used = usedPoints(a);
    const size_t n = a.points.size() + a.triangles.size();
    std::vector<double> d(n, -1);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t i = r.begin(); i != r.end(); ++i) {
            Vec3d p;
            if (samplePoint(a, used, i, p)) d[i] = std::min(buckets(p, reach, 0), reach);
        }
    });
    double sum = 0;
    size_t count = 0;
    for (double v : d)
        if (v >= 0) sum += v, ++count;
    return count ? sum / double(count) : 0;
}

double meshDistance(const TriangleMesh& a, const TriangleMesh& b, double reach)
{
    if (a.triangles.empty()) return 0;
    if (b.triangles.empty() || !(reach > 0)) return std::numeric_limits<double>::infinity();
    const Buckets buckets = bucketsOf(b, reach);
    // a's points each once (those of its triangles), then its triangles' middles, for a middle
    // that bulges away from b; each only as far as it could raise the largest found so far
    const std::vector<uint8_t> used = usedPoints(a);
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, a.points.size() + a.triangles.size()), 0.0,
        [&](const tbb::blocked_range<size_t>& r, double worst) {
            for (size_t i = r.begin(); i != r.end(); ++i) {
                Vec3d p;
                if (samplePoint(a, used, i, p)) worst = std::max(worst, buckets(p, reach, worst));
            }
            return worst;
        },
        [](double x, double y) { return std::max(x, y); });
}

} // namespace fluidsurf
