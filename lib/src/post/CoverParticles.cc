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

/// The points within `radius` of each centre: centre c's are points[start[c], start[c + 1]),
/// ascending. Each centre is listed in the 27 cells of side `radius` around its own (an
/// open-addressing table of the cells, which are few), so that a point looks in one cell; most
/// points find none. Blocks of points in order, then counted out by centre: the same lists for
/// any thread count, without a sort.
struct NearPoints
{
    std::vector<uint32_t> start, points;
};

NearPoints pointsNear(const TriangleMesh& mesh, const std::vector<Vec3f>& centres, double radius)
{
    auto cell = [&](float x) { return int64_t(std::floor(double(x) / radius)); };
    auto key = [](int64_t x, int64_t y, int64_t z) {
        constexpr uint64_t m = (1u << 21) - 1; // (cells 21 bits a side: a wrap only aliases)
        return (uint64_t(x) & m) << 42 | (uint64_t(y) & m) << 21 | (uint64_t(z) & m);
    };
    std::vector<std::pair<uint64_t, uint32_t>> listed; // (cell, centre)
    listed.reserve(27 * centres.size());
    for (uint32_t c = 0; c < centres.size(); ++c) {
        const Vec3f& p = centres[c];
        const int64_t x = cell(p.x), y = cell(p.y), z = cell(p.z);
        for (int64_t dz = -1; dz <= 1; ++dz)
            for (int64_t dy = -1; dy <= 1; ++dy)
                for (int64_t dx = -1; dx <= 1; ++dx)
                    listed.push_back({key(x + dx, y + dy, z + dz), c});
    }
    std::sort(listed.begin(), listed.end());
    // the table: a cell's slot holds the first of its entries in `listed`
    size_t size = 64;
    while (size < 2 * listed.size())
        size *= 2;
    const size_t mask = size - 1;
    std::vector<uint32_t> table(size, UINT32_MAX);
    auto slotOf = [&](uint64_t k) { return size_t((k * 0x9e3779b97f4a7c15ull) >> 20) & mask; };
    for (size_t i = 0; i < listed.size(); ++i) {
        if (i > 0 && listed[i].first == listed[i - 1].first) continue;
        size_t slot = slotOf(listed[i].first);
        while (table[slot] != UINT32_MAX)
            slot = (slot + 1) & mask;
        table[slot] = uint32_t(i);
    }
    const double r2 = radius * radius;
    constexpr size_t kBlock = 1 << 14;
    const size_t blocks = (mesh.points.size() + kBlock - 1) / kBlock;
    std::vector<std::vector<std::pair<uint32_t, uint32_t>>> found(blocks); // (centre, point)
    tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
        auto& out = found[b];
        for (size_t v = b * kBlock; v < std::min(mesh.points.size(), (b + 1) * kBlock); ++v) {
            const Vec3f& p = mesh.points[v];
            const uint64_t k = key(cell(p.x), cell(p.y), cell(p.z));
            for (size_t slot = slotOf(k); table[slot] != UINT32_MAX; slot = (slot + 1) & mask) {
                if (listed[table[slot]].first != k) continue;
                for (size_t i = table[slot]; i < listed.size() && listed[i].first == k; ++i) {
                    const uint32_t c = listed[i].second;
                    if ((toVec3d(p) - toVec3d(centres[c])).lengthSqr() < r2)
                        out.push_back({c, uint32_t(v)});
                }
                break;
            }
        }
    });
    NearPoints near;
    near.start.assign(centres.size() + 1, 0);
    for (const auto& part : found)
        for (const auto& cp : part)
            ++near.start[cp.first + 1];
    for (size_t c = 0; c < centres.size(); ++c)
        near.start[c + 1] += near.start[c];
    near.points.resize(near.start.back());
    std::vector<uint32_t> fill(near.start.begin(), near.start.end() - 1);
    for (const auto& part : found) // (blocks in order: each centre's points ascending)
        for (const auto& cp : part)
            near.points[fill[cp.first]++] = cp.second;
    return near;
}

/// A small map of point or triangle numbers to a state, for one patch at a time: open
/// addressing over a table of at least twice the keys it is set up for, cleared by the slots it
/// used. One per thread (the mesh-sized stamp arrays it replaces were one per run).
class LocalMap
{
public:
    void reset(size_t expected)
    {
        size_t size = 64;
        while (size < 2 * expected)
            size *= 2;
        if (size > mKeys.size()) {
            mKeys.assign(size, kEmpty), mStates.assign(size, 0);
        } else {
            for (uint32_t slot : mUsed)
                mKeys[slot] = kEmpty;
        }
        mUsed.clear();
        mMask = mKeys.size() - 1;
    }
    /// key's state; 0 if absent
    uint8_t get(uint32_t key) const
    {
        for (size_t slot = slotOf(key);; slot = (slot + 1) & mMask) {
            if (mKeys[slot] == key) return mStates[slot];
            if (mKeys[slot] == kEmpty) return 0;
        }
    }
    void set(uint32_t key, uint8_t state)
    {
        size_t slot = slotOf(key);
        while (mKeys[slot] != key && mKeys[slot] != kEmpty)
            slot = (slot + 1) & mMask;
        if (mKeys[slot] == kEmpty) mKeys[slot] = key, mUsed.push_back(uint32_t(slot));
        mStates[slot] = state;
    }

private:
    static constexpr uint32_t kEmpty = UINT32_MAX;
    size_t slotOf(uint32_t key) const { return size_t((key * 0x9e3779b1u) >> 7) & mMask; }
    std::vector<uint32_t> mKeys, mUsed;
    std::vector<uint8_t> mStates;
    size_t mMask = 0;
};

/// The surface near one centre: its points and the triangles around them, each in the order
/// first met. What one centre reads and moves: the triangles around its points (each read
/// whole), and its points; the normals of its points only (their triangles are its own).
class Patch
{
public:
    Patch(TriangleMesh& mesh, const VertexTriangles& around) : mMesh(mesh), mAround(around) {}

    /// The patch of points [first, last).
    void reset(const uint32_t* first, const uint32_t* last)
    {
        points.assign(first, last), tris.clear(), inner.clear();
        mPoints.reset(points.size()), mTris.reset(6 * points.size());
        for (uint32_t v : points)
            mPoints.set(v, kIn);
        for (uint32_t v : points)
            for (uint32_t i = mAround.start[v]; i < mAround.start[v + 1]; ++i) {
                const uint32_t t = mAround.tris[i];
                if (mTris.get(t)) continue;
                mTris.set(t, kIn), tris.push_back(t);
                const auto& c = mMesh.triangles[t];
                if (mPoints.get(c[0]) && mPoints.get(c[1]) && mPoints.get(c[2])) inner.push_back(t);
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

    /// The nearest point of the inner triangles (all corners the patch's: a bump's nearest
    /// point is within a voxel of its centre, the patch's border 3.6 voxels away).
    Nearest nearest(const Vec3d& p) const
    {
        Nearest n;
        double best = std::numeric_limits<double>::infinity();
        Vec3d weights(0.0);
        for (uint32_t t : inner) {
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

    /// The patch's points joined to triangle `from` (an inner one) through its triangles, in the
    /// order met.
    std::vector<uint32_t> sheetOf(uint32_t from)
    {
        std::vector<uint32_t> sheet, stack{from};
        mTris.set(from, kMet);
        while (!stack.empty()) {
            const uint32_t t = stack.back();
            stack.pop_back();
            for (uint32_t v : mMesh.triangles[t]) {
                if (mPoints.get(v) != kIn) continue; // not the patch's, or met
                mPoints.set(v, kMet), sheet.push_back(v);
                for (uint32_t i = mAround.start[v]; i < mAround.start[v + 1]; ++i) {
                    const uint32_t u = mAround.tris[i]; // (a patch point's: the patch's)
                    if (mTris.get(u) == kIn) mTris.set(u, kMet), stack.push_back(u);
                }
            }
        }
        return sheet;
    }

    std::vector<uint32_t> points, tris, inner;

private:
    static constexpr uint8_t kIn = 1, kMet = 2;
    TriangleMesh& mMesh;
    const VertexTriangles& mAround;
    LocalMap mPoints, mTris;
};

} // namespace

namespace {

enum Outcome : uint8_t { kInside, kFar, kBump, kCovered, kLeft };

/// One centre's bumps on the patch set up for it, from its nearest point n (outside, or inside
/// by less than half the margin): kCovered, kLeft (taken back), or kInside (found inside at its
/// turn, after the bumps of others).
Outcome bumpOver(TriangleMesh& mesh, Patch& patch, const Vec3d& p, Patch::Nearest n,
                 const CoverParams& params)
{
    if (n.depth <= -0.5 * params.margin) return kInside;
    const double reach2 = params.reach * params.reach;
    const std::vector<uint32_t> sheet = patch.sheetOf(n.tri);
    std::vector<Vec3f> start, moved;
    std::vector<Vec3d> faces;
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
    bool folded = n.depth > -0.5 * params.margin; // (not there after all: taken back too)
    constexpr double cos60 = 0.5;
    for (size_t k = 0; k < patch.tris.size() && !folded; ++k) {
        if (faces[k].lengthSqr() == 0) continue; // (no direction to keep)
        const Vec3d now = sideCross(mesh.points, mesh.triangles[patch.tris[k]]);
        folded = !(now.dot(faces[k]) > cos60 * now.length() * faces[k].length());
    }
    if (!folded) return kCovered;
    for (size_t k = 0; k < sheet.size(); ++k)
        mesh.points[sheet[k]] = start[k];
    return kLeft;
}

} // namespace

namespace {

/// coverParticles for centres [first, last).
CoverStats coverSome(TriangleMesh& mesh, const VertexTriangles& around, const Vec3f* first,
                     const Vec3f* last, const CoverParams& params)
{
    CoverStats st;
    const std::vector<Vec3f> centres(first, last);
    // every point a bump may move, and every triangle that may hold the nearest point
    const NearPoints near =
        pointsNear(mesh, centres, params.reach + params.maxDepth + params.margin);
    const size_t n = centres.size();
    auto patchOf = [&](Patch& patch, size_t c) {
        patch.reset(near.points.data() + near.start[c], near.points.data() + near.start[c + 1]);
    };
    const Patch exemplar(mesh, around);
    tbb::enumerable_thread_specific<Patch> patches(exemplar);
    // 1. Each centre against the surface as it is (nothing moves yet): inside, too far out
    // (or no point near), or one to bump.
    std::vector<uint8_t> outcome(n);
    tbb::parallel_for(size_t(0), n, [&](size_t c) {
        Patch& patch = patches.local();
        patchOf(patch, c);
        if (patch.inner.empty()) {
            outcome[c] = kFar;
            return;
        }
        const Patch::Nearest at = patch.nearest(toVec3d(centres[c]));
        outcome[c] = at.depth <= -0.5 * params.margin ? kInside
                     : at.depth > params.maxDepth     ? kFar
                                                      : kBump;
    });
    // 2. The bumps in rounds: a centre goes in the round after the last one of a centre before
    // it (in their order) that shares a triangle with it, since that one moves what it reads.
    // Centres of one round touch nothing in common: in parallel, with the bits of going one
    // after the other.
    std::vector<uint32_t> roundOf(n, 0), lastRound(mesh.triangles.size(), 0);
    uint32_t rounds = 0;
    for (size_t c = 0; c < n; ++c) {
        if (outcome[c] != kBump) continue;
        uint32_t round = 0;
        for (uint32_t i = near.start[c]; i < near.start[c + 1]; ++i) {
            const uint32_t v = near.points[i];
            for (uint32_t k = around.start[v]; k < around.start[v + 1]; ++k)
                round = std::max(round, lastRound[around.tris[k]]);
        }
        roundOf[c] = ++round, rounds = std::max(rounds, round);
        for (uint32_t i = near.start[c]; i < near.start[c + 1]; ++i) {
            const uint32_t v = near.points[i];
            for (uint32_t k = around.start[v]; k < around.start[v + 1]; ++k)
                lastRound[around.tris[k]] = round;
        }
    }
    std::vector<uint32_t> firstOf(rounds + 2, 0), order;
    for (size_t c = 0; c < n; ++c)
        if (roundOf[c]) ++firstOf[roundOf[c] + 1];
    for (uint32_t r = 1; r <= rounds; ++r)
        firstOf[r + 1] += firstOf[r];
    order.resize(firstOf[rounds + 1]);
    {
        std::vector<uint32_t> fill(firstOf);
        for (size_t c = 0; c < n; ++c)
            if (roundOf[c]) order[fill[roundOf[c]]++] = uint32_t(c);
    }
    for (uint32_t r = 1; r <= rounds; ++r)
        tbb::parallel_for(firstOf[r], firstOf[r + 1], [&](uint32_t i) {
            const size_t c = order[i];
            Patch& patch = patches.local();
            patchOf(patch, c);
            const Vec3d p = toVec3d(centres[c]);
            outcome[c] = bumpOver(mesh, patch, p, patch.nearest(p), params);
        });
    for (uint8_t o : outcome)
        st.covered += o == kCovered, st.left += o == kLeft || o == kFar;
    return st;
}

} // namespace

CoverStats coverParticles(TriangleMesh& mesh, const VertexTriangles& around,
                          const std::vector<Vec3f>& centres, const CoverParams& params)
{
    CoverStats st;
    if (mesh.triangles.empty()) return st;
    // A few thousand centres out as a rule, about 100 points near each; a surface that misses
    // most of a frame's centres (a level far from the default) must not take memory by the
    // hundred points per particle: so many at a time.
    constexpr size_t kCentres = 1 << 14;
    for (size_t c = 0; c < centres.size(); c += kCentres) {
        const size_t end = std::min(centres.size(), c + kCentres);
        const CoverStats part =
            coverSome(mesh, around, centres.data() + c, centres.data() + end, params);
        st.covered += part.covered, st.left += part.left;
    }
    return st;
}

} // namespace post
} // namespace fluidsurf
