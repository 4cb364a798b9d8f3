// CoverParticles.cc - bumps of the surface over the particle centres it leaves outside (see the
// header).
//
// Why a bump along q -> centre and not the points' own normals: one direction for the whole
// bump is a smooth field of moves, which turns no triangle where its slope stays under one (the
// bump's is at most 1.54 (depth + margin) / reach); moves along the points' normals spread apart
// on a tip and crowd together in a crease. Why only the sheet around q, facing the centre: a
// thin sheet's other side lies within reach, and moving it along with this side would uncover
// the particles under it.
#include "post/CoverParticles.h"

#include "util/TriangleDistance.h"
#include "util/Vec3d.h"

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <limits>
#include <unordered_map>
#include <utility>

namespace fluidsurf {
namespace post {

namespace {

/// The centres within `radius` of each point, as (centre, point) pairs sorted: each centre is
/// listed in the 27 cells of side `radius` around its own, so that a point looks in one cell.
std::vector<std::pair<uint32_t, uint32_t>>
pointsNear(const TriangleMesh& mesh, const std::vector<Vec3f>& centres, double radius)
{
    auto cell = [&](double x) { return int64_t(std::floor(x / radius)); };
    auto key = [](int64_t x, int64_t y, int64_t z) {
        constexpr uint64_t m = (1u << 21) - 1; // (cells 21 bits a side: a wrap only aliases)
        return (uint64_t(x) & m) << 42 | (uint64_t(y) & m) << 21 | (uint64_t(z) & m);
    };
    std::unordered_map<uint64_t, std::vector<uint32_t>> cells;
    for (uint32_t c = 0; c < centres.size(); ++c) {
        const Vec3f& p = centres[c];
        const int64_t x = cell(p.x), y = cell(p.y), z = cell(p.z);
        for (int64_t dz = -1; dz <= 1; ++dz)
            for (int64_t dy = -1; dy <= 1; ++dy)
                for (int64_t dx = -1; dx <= 1; ++dx)
                    cells[key(x + dx, y + dy, z + dz)].push_back(c);
    }
    const double r2 = radius * radius;
    tbb::enumerable_thread_specific<std::vector<std::pair<uint32_t, uint32_t>>> found;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, mesh.points.size(), 1 << 14),
                      [&](const tbb::blocked_range<size_t>& r) {
                          auto& out = found.local();
                          for (size_t v = r.begin(); v != r.end(); ++v) {
                              const Vec3f& p = mesh.points[v];
                              const auto it = cells.find(key(cell(p.x), cell(p.y), cell(p.z)));
                              if (it == cells.end()) continue;
                              for (uint32_t c : it->second)
                                  if ((toVec3d(p) - toVec3d(centres[c])).lengthSqr() < r2)
                                      out.push_back({c, uint32_t(v)});
                          }
                      });
    std::vector<std::pair<uint32_t, uint32_t>> pairs;
    for (const auto& part : found)
        pairs.insert(pairs.end(), part.begin(), part.end());
    std::sort(pairs.begin(), pairs.end());
    return pairs;
}

/// The surface near one centre: its points and the triangles around them, each in the order
/// first met. Membership by stamps on the mesh's points and triangles (2 id + 1: the patch's,
/// 2 id + 2: met by sheetOf too), so that a patch is set up in time of its own size.
class Patch
{
public:
    Patch(TriangleMesh& mesh, const VertexTriangles& around)
        : mMesh(mesh), mAround(around), mPointStamp(mesh.points.size(), 0),
          mTriStamp(mesh.triangles.size(), 0)
    {
    }

    void reset(const std::pair<uint32_t, uint32_t>* first,
               const std::pair<uint32_t, uint32_t>* last)
    {
        ++mId;
        points.clear(), tris.clear();
        for (auto* p = first; p != last; ++p) {
            const uint32_t v = p->second;
            points.push_back(v), mPointStamp[v] = 2 * mId + 1;
            for (uint32_t i = mAround.start[v]; i < mAround.start[v + 1]; ++i) {
                const uint32_t t = mAround.tris[i];
                if (mTriStamp[t] != 2 * mId + 1) mTriStamp[t] = 2 * mId + 1, tris.push_back(t);
            }
        }
    }

    /// The unit area-weighted normal of point v (zero where its triangles cancel).
    Vec3d normal(uint32_t v) const
    {
        const Vec3d n = areaNormal(mMesh.points, mMesh, mAround, v);
        const double len = n.length();
        return len > 0 ? n / len : Vec3d(0.0);
    }

    struct Nearest
    {
        Vec3d point{0.0}, normal{0.0};
        double depth = 0; ///< signed distance of the centre: > 0 outside
        uint32_t tri = 0;
    };

    Nearest nearest(const Vec3d& p) const
    {
        Nearest n;
        double best = std::numeric_limits<double>::infinity();
        Vec3d weights(0.0);
        for (uint32_t t : tris) {
            const auto& tri = mMesh.triangles[t];
            const Vec3d a = toVec3d(mMesh.points[tri[0]]), b = toVec3d(mMesh.points[tri[1]]),
                        c = toVec3d(mMesh.points[tri[2]]);
            const Vec3d w = nearestOnTriangle(p, a, b, c);
            const Vec3d q = a * w[0] + b * w[1] + c * w[2];
            const double d2 = (p - q).lengthSqr();
            if (d2 < best) best = d2, n.point = q, n.tri = t, weights = w;
        }
        const auto& tri = mMesh.triangles[n.tri];
        for (int k = 0; k < 3; ++k)
            n.normal += normal(tri[k]) * weights[k];
        const double len = n.normal.length();
        if (len > 0) n.normal /= len;
        n.depth = (p - n.point).dot(n.normal) >= 0 ? std::sqrt(best) : -std::sqrt(best);
        return n;
    }

    /// The patch's points joined to triangle `from` (one of its own) through its triangles, in
    /// the order met.
    std::vector<uint32_t> sheetOf(uint32_t from)
    {
        const uint32_t in = 2 * mId + 1, met = 2 * mId + 2;
        std::vector<uint32_t> sheet, stack{from};
        mTriStamp[from] = met;
        while (!stack.empty()) {
            const uint32_t t = stack.back();
            stack.pop_back();
            for (uint32_t v : mMesh.triangles[t]) {
                if (mPointStamp[v] != in) continue; // not the patch's, or met
                mPointStamp[v] = met, sheet.push_back(v);
                for (uint32_t i = mAround.start[v]; i < mAround.start[v + 1]; ++i) {
                    const uint32_t u = mAround.tris[i]; // (a patch point's: the patch's)
                    if (mTriStamp[u] == in) mTriStamp[u] = met, stack.push_back(u);
                }
            }
        }
        return sheet;
    }

    std::vector<uint32_t> points, tris;

private:
    TriangleMesh& mMesh;
    const VertexTriangles& mAround;
    std::vector<uint32_t> mPointStamp, mTriStamp;
    uint32_t mId = 0;
};

} // namespace

CoverStats coverParticles(TriangleMesh& mesh, const VertexTriangles& around,
                          const std::vector<Vec3f>& centres, const CoverParams& params)
{
    CoverStats st;
    if (centres.empty() || mesh.triangles.empty()) return st;
    // every point a bump may move, and every triangle that may hold the nearest point
    const double radius = params.reach + params.maxDepth + params.margin;
    const std::vector<std::pair<uint32_t, uint32_t>> pairs = pointsNear(mesh, centres, radius);
    Patch patch(mesh, around);
    std::vector<Vec3f> start, moved;
    std::vector<Vec3d> faces;
    const double cos60 = 0.5, reach2 = params.reach * params.reach;
    for (size_t at = 0; at < pairs.size();) {
        size_t end = at;
        while (end < pairs.size() && pairs[end].first == pairs[at].first)
            ++end;
        const Vec3d p = toVec3d(centres[pairs[at].first]);
        patch.reset(pairs.data() + at, pairs.data() + end);
        at = end;
        if (patch.tris.empty()) continue;
        Patch::Nearest n = patch.nearest(p);
        if (n.depth <= -0.5 * params.margin) continue; // inside already
        if (n.depth > params.maxDepth) {
            ++st.left;
            continue;
        }
        const std::vector<uint32_t> sheet = patch.sheetOf(n.tri);
        start.clear(), faces.clear();
        for (uint32_t v : sheet)
            start.push_back(mesh.points[v]);
        for (uint32_t t : patch.tris)
            faces.push_back(sideCross(mesh.points, mesh.triangles[t]));
        for (int bump = 0; bump < 6 && n.depth > -0.5 * params.margin; ++bump) {
            // outward: towards the centre from outside, away from it from inside
            const Vec3d from = n.depth > 0 ? p - n.point : n.point - p;
            const double len = from.length();
            const Vec3d dir = len > 1e-9 * params.reach ? from / len : n.normal;
            const double height = n.depth + params.margin;
            moved.clear();
            for (uint32_t v : sheet) { // (all from the same positions)
                const Vec3d x = toVec3d(mesh.points[v]);
                const double s2 = (x - n.point).lengthSqr() / reach2;
                const double facing = std::clamp(0.5 + patch.normal(v).dot(dir), 0.0, 1.0);
                const double w = s2 < 1 ? (1 - s2) * (1 - s2) * facing : 0;
                moved.push_back(toVec3f(x + dir * (height * w)));
            }
            for (size_t k = 0; k < sheet.size(); ++k)
                mesh.points[sheet[k]] = moved[k];
            n = patch.nearest(p);
        }
        bool folded = n.depth > -0.5 * params.margin;
        for (size_t k = 0; k < patch.tris.size() && !folded; ++k) {
            if (faces[k].lengthSqr() == 0) continue; // (no direction to keep)
            const Vec3d now = sideCross(mesh.points, mesh.triangles[patch.tris[k]]);
            folded = !(now.dot(faces[k]) > cos60 * now.length() * faces[k].length());
        }
        if (folded) {
            for (size_t k = 0; k < sheet.size(); ++k)
                mesh.points[sheet[k]] = start[k];
            ++st.left;
        } else {
            ++st.covered;
        }
    }
    return st;
}

} // namespace post
} // namespace fluidsurf
