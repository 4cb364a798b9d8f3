// MeshDistance.h - an independent point-to-mesh distance for the tests (a bucket grid of
// triangles, exact point-triangle distance), to bound the Hausdorff distance between meshes.
#pragma once

#include <fluidsurf/Mesh.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <unordered_map>
#include <vector>

namespace fluidsurf {
namespace test {

using P3 = std::array<double, 3>;

inline P3 sub(const P3& a, const P3& b)
{
    return {a[0] - b[0], a[1] - b[1], a[2] - b[2]};
}
inline double dot(const P3& a, const P3& b)
{
    return a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
}
inline P3 cross(const P3& a, const P3& b)
{
    return {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0]};
}
inline P3 toP3(const Vec3f& v)
{
    return {v.x, v.y, v.z};
}

inline double segmentDistance(const P3& p, const P3& a, const P3& b)
{
    const P3 ab = sub(b, a), ap = sub(p, a);
    const double len2 = dot(ab, ab);
    const double t = len2 > 0 ? std::clamp(dot(ap, ab) / len2, 0.0, 1.0) : 0.0;
    const P3 q = {a[0] + t * ab[0] - p[0], a[1] + t * ab[1] - p[1], a[2] + t * ab[2] - p[2]};
    return std::sqrt(dot(q, q));
}

/// Distance from p to triangle abc: to the plane when the projection falls inside, else to the
/// nearest edge.
inline double triangleDistance(const P3& p, const P3& a, const P3& b, const P3& c)
{
    const P3 n = cross(sub(b, a), sub(c, a));
    const double n2 = dot(n, n);
    if (n2 > 0) {
        const double h = dot(sub(p, a), n) / n2;
        const P3 q = {p[0] - h * n[0], p[1] - h * n[1], p[2] - h * n[2]};
        const bool in = dot(cross(sub(b, a), sub(q, a)), n) >= 0 &&
                        dot(cross(sub(c, b), sub(q, b)), n) >= 0 &&
                        dot(cross(sub(a, c), sub(q, c)), n) >= 0;
        if (in) return std::abs(h) * std::sqrt(n2);
    }
    return std::min({segmentDistance(p, a, b), segmentDistance(p, b, c), segmentDistance(p, c, a)});
}

/// Distances to a mesh up to `reach`; farther points report +inf.
class MeshDistance
{
public:
    MeshDistance(const TriangleMesh& mesh, double reach) : mMesh(mesh), mCell(reach)
    {
        for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
            P3 lo{1e300, 1e300, 1e300}, hi{-1e300, -1e300, -1e300};
            for (uint32_t v : mesh.triangles[t])
                for (int a = 0; a < 3; ++a) {
                    lo[a] = std::min(lo[a], double(toP3(mesh.points[v])[a]));
                    hi[a] = std::max(hi[a], double(toP3(mesh.points[v])[a]));
                }
            for (int64_t x = cell(lo[0]); x <= cell(hi[0]); ++x)
                for (int64_t y = cell(lo[1]); y <= cell(hi[1]); ++y)
                    for (int64_t z = cell(lo[2]); z <= cell(hi[2]); ++z)
                        mBuckets[key(x, y, z)].push_back(t);
        }
    }

    double operator()(const P3& p) const
    {
        double best = std::numeric_limits<double>::infinity();
        for (int64_t x = cell(p[0] - mCell); x <= cell(p[0] + mCell); ++x)
            for (int64_t y = cell(p[1] - mCell); y <= cell(p[1] + mCell); ++y)
                for (int64_t z = cell(p[2] - mCell); z <= cell(p[2] + mCell); ++z) {
                    auto it = mBuckets.find(key(x, y, z));
                    if (it == mBuckets.end()) continue;
                    for (uint32_t t : it->second) {
                        const auto& tri = mMesh.triangles[t];
                        best = std::min(best, triangleDistance(p, toP3(mMesh.points[tri[0]]),
                                                               toP3(mMesh.points[tri[1]]),
                                                               toP3(mMesh.points[tri[2]])));
                    }
                }
        return best <= mCell ? best : std::numeric_limits<double>::infinity();
    }

private:
    int64_t cell(double v) const { return int64_t(std::floor(v / mCell)); }
    static uint64_t key(int64_t x, int64_t y, int64_t z)
    {
        return (uint64_t(x & 0x1fffff) << 42) | (uint64_t(y & 0x1fffff) << 21) |
               uint64_t(z & 0x1fffff);
    }
    const TriangleMesh& mMesh;
    double mCell;
    std::unordered_map<uint64_t, std::vector<uint32_t>> mBuckets;
};

/// Largest distance from the vertices and triangle centroids of a to mesh b (+inf beyond reach).
inline double oneSidedDistance(const TriangleMesh& a, const TriangleMesh& b, double reach)
{
    const MeshDistance dist(b, reach);
    double worst = 0;
    for (const Vec3f& v : a.points)
        worst = std::max(worst, dist(toP3(v)));
    for (const auto& t : a.triangles) {
        P3 c{0, 0, 0};
        for (uint32_t v : t)
            for (int k = 0; k < 3; ++k)
                c[k] += toP3(a.points[v])[k] / 3;
        worst = std::max(worst, dist(c));
    }
    return worst;
}

} // namespace test
} // namespace fluidsurf
