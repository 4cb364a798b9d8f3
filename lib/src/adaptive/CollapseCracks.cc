// CollapseCracks.cc - see CollapseCracks.h. Each merge is checked on the triangles around the
// end it merges into, kept in small lists for the vertices of the cracks only.
#include "adaptive/CollapseCracks.h"

#include <algorithm>
#include <array>
#include <cmath>

namespace fluidsurf {
namespace adaptive {

namespace {

using Triangle = std::array<uint32_t, 3>;

int cornerOf(const Triangle& t, uint32_t v)
{
    return t[0] == v ? 0 : t[1] == v ? 1 : t[2] == v ? 2 : -1;
}

/// Twice the area vector of a triangle, in double.
std::array<double, 3> areaVector(const Vec3f& a, const Vec3f& b, const Vec3f& c)
{
    const double u[3] = {double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
    const double v[3] = {double(c.x) - a.x, double(c.y) - a.y, double(c.z) - a.z};
    return {u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]};
}

double squaredLength(const Vec3f& a, const Vec3f& b)
{
    const double d[3] = {double(b.x) - a.x, double(b.y) - a.y, double(b.z) - a.z};
    return d[0] * d[0] + d[1] * d[1] + d[2] * d[2];
}

/// Whether triangle t keeps its side and some area when its corner at `from` moves to `to`.
bool keepsItsShape(const TriangleMesh& mesh, const Triangle& t, uint32_t from, uint32_t to)
{
    Triangle moved = t;
    moved[cornerOf(t, from)] = to;
    const auto& p = mesh.points;
    const auto before = areaVector(p[t[0]], p[t[1]], p[t[2]]);
    const auto after = areaVector(p[moved[0]], p[moved[1]], p[moved[2]]);
    const double side = before[0] * after[0] + before[1] * after[1] + before[2] * after[2];
    const double twiceArea =
        std::sqrt(after[0] * after[0] + after[1] * after[1] + after[2] * after[2]);
    const double longest =
        std::max({squaredLength(p[moved[0]], p[moved[1]]), squaredLength(p[moved[1]], p[moved[2]]),
                  squaredLength(p[moved[2]], p[moved[0]])});
    // Well clear of MeshCheck's degenerate area (1e-10 of the longest side squared).
    return side > 0 && twiceArea > 1e-6 * longest;
}

/// Whether the link of a vertex (X -> Y for each of its triangles X, Y in walking order) has
/// every vertex once as a start and once as an end at most, and, if it closes into a cycle
/// anywhere, is that one cycle (one fan around the vertex, no two fans touching there).
bool isOneFan(std::vector<std::pair<uint32_t, uint32_t>>& link)
{
    std::sort(link.begin(), link.end());
    for (size_t i = 1; i < link.size(); ++i)
        if (link[i].first == link[i - 1].first) return false;
    std::vector<uint32_t> ends(link.size());
    for (size_t i = 0; i < link.size(); ++i)
        ends[i] = link[i].second;
    std::sort(ends.begin(), ends.end());
    if (std::adjacent_find(ends.begin(), ends.end()) != ends.end()) return false;
    // Walk from every start that is no end (paths), then what is left is cycles.
    auto next = [&](uint32_t x) {
        const auto it = std::lower_bound(link.begin(), link.end(), std::make_pair(x, 0u));
        return it != link.end() && it->first == x ? size_t(it - link.begin()) : link.size();
    };
    std::vector<char> seen(link.size(), 0);
    size_t paths = 0, cycles = 0;
    for (size_t i = 0; i < link.size(); ++i) {
        if (std::binary_search(ends.begin(), ends.end(), link[i].first)) continue;
        ++paths;
        for (size_t k = i; k < link.size() && !seen[k]; k = next(link[k].second))
            seen[k] = 1;
    }
    for (size_t i = 0; i < link.size(); ++i) {
        if (seen[i]) continue;
        ++cycles;
        for (size_t k = i; k < link.size() && !seen[k]; k = next(link[k].second))
            seen[k] = 1;
    }
    return cycles == 0 || (cycles == 1 && paths == 0);
}

class Merger
{
public:
    Merger(TriangleMesh& mesh, const std::vector<CrackPath>& paths, std::vector<char>& removed)
        : mMesh(mesh), mRemoved(removed), mSlot(mesh.points.size(), -1)
    {
        mRemoved.assign(mesh.triangles.size(), 0);
        for (const CrackPath& p : paths) {
            track(p.a), track(p.b);
            for (uint32_t v : p.between)
                track(v);
        }
        for (uint32_t t = 0; t < mesh.triangles.size(); ++t)
            for (uint32_t v : mesh.triangles[t])
                if (mSlot[v] >= 0) mAround[size_t(mSlot[v])].push_back(t);
    }

    /// Merges vertex `from` into `to` if the checks in the header allow it.
    bool merge(uint32_t from, uint32_t to)
    {
        std::vector<uint32_t>& aroundFrom = mAround[size_t(mSlot[from])];
        std::vector<uint32_t>& aroundTo = mAround[size_t(mSlot[to])];
        std::vector<uint32_t> moved, flattened;
        for (uint32_t t : aroundFrom) {
            if (mRemoved[t]) continue;
            (cornerOf(mMesh.triangles[t], to) >= 0 ? flattened : moved).push_back(t);
        }
        if (flattened.empty()) return false; // not neighbours
        std::vector<std::pair<uint32_t, uint32_t>> link;
        auto linkOf = [&](const Triangle& t, uint32_t v) {
            const int k = cornerOf(t, v);
            link.emplace_back(t[(k + 1) % 3], t[(k + 2) % 3]);
        };
        for (uint32_t t : aroundTo)
            if (!mRemoved[t] && std::find(flattened.begin(), flattened.end(), t) == flattened.end())
                linkOf(mMesh.triangles[t], to);
        for (uint32_t t : moved) {
            if (!keepsItsShape(mMesh, mMesh.triangles[t], from, to)) return false;
            Triangle m = mMesh.triangles[t];
            m[cornerOf(m, from)] = to;
            linkOf(m, to);
        }
        if (!isOneFan(link)) return false;
        for (uint32_t t : flattened)
            mRemoved[t] = 1;
        for (uint32_t t : moved) {
            Triangle& m = mMesh.triangles[t];
            m[cornerOf(m, from)] = to;
            aroundTo.push_back(t);
        }
        aroundFrom.clear();
        return true;
    }

private:
    void track(uint32_t v)
    {
        if (mSlot[v] >= 0) return;
        mSlot[v] = int32_t(mAround.size());
        mAround.emplace_back();
    }

    TriangleMesh& mMesh;
    std::vector<char>& mRemoved;
    std::vector<int32_t> mSlot;                 // per vertex: its list in mAround, or -1
    std::vector<std::vector<uint32_t>> mAround; // triangles holding a tracked vertex
};

} // namespace

size_t collapseCracks(TriangleMesh& mesh, std::vector<CrackPath>& paths, std::vector<char>& removed)
{
    Merger merger(mesh, paths, removed);
    size_t merged = 0;
    for (CrackPath& path : paths) {
        const size_t n = path.between.size();
        size_t toA = n / 2;
        if (n % 2) {
            // Nearer b by a clear margin: to b; else to a. The margin keeps the choice the same
            // under rounding (a CPU without AVX2 sums the field on 4 lanes, and its values
            // differ from the GPU's by about 1e-6 r), and a
            // middle point is often as near one end as the other (a flat face).
            const Vec3f& middle = mesh.points[path.between[n / 2]];
            const double da = squaredLength(middle, mesh.points[path.a]),
                         db = squaredLength(middle, mesh.points[path.b]);
            if (!(db < da * (1 - 1e-3))) ++toA;
        }
        std::vector<char> gone(n, 0);
        for (size_t i = 0; i < toA && merger.merge(path.between[i], path.a); ++i)
            gone[i] = 1;
        for (size_t i = n; i > toA && merger.merge(path.between[i - 1], path.b); --i)
            gone[i - 1] = 1;
        std::vector<uint32_t> left;
        for (size_t i = 0; i < n; ++i)
            if (!gone[i]) left.push_back(path.between[i]);
        merged += n - left.size();
        path.between = std::move(left);
    }
    return merged;
}

} // namespace adaptive
} // namespace fluidsurf
