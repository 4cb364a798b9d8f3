// StepGuard.cc - how far one collapse moves the surface (see StepGuard.h).
//
// A flat fan is let through without a point tested (isFlat), from the normals the caller has
// found already and the fans where the caller keeps them; only otherwise are the fans copied and
// set up once (NearTriangle) for the dozens of questions the collapse asks, and each point is
// tried first against the triangle it came from and those by its ring vertex, where it lies as
// a rule.
#include "post/StepGuard.h"

#include <algorithm>
#include <cmath>

namespace fluidsurf {
namespace post {

void StepGuard::start(const Vec3d& q, const std::array<Vec3d, 4> (&gone)[2], const Ids (&ids)[2],
                      const uint32_t (&across)[2], const Vec3d (&acrossPoints)[2])
{
    mQ = q;
    for (int g = 0; g < 2; ++g)
        mGone[g] = gone[g], mGoneIds[g] = ids[g], mAcross[g] = across[g],
        mAcrossPoint[g] = acrossPoints[g];
}

void StepGuard::prepare()
{
    mOld.clear(), mOldIds.clear(), mAfter.clear(), mNewIds.clear(), mFar.clear();
    for (int g = 0; g < 2; ++g) {
        const auto& [x, u, w, n] = mGone[g];
        mOld.emplace_back(x, u, w);
        mOldIds.push_back(mGoneIds[g]);
        // the old triangle's middle, standing for the surface it covered: near the same
        // triangle moved when that moved it less than the bound; a segment has none
        const Vec3d middle = (x + u + w) / 3.0;
        if (((mQ + mQ + mAcrossPoint[g]) / 3.0 - middle).length() > mBound)
            mFar.push_back({middle, kNone, mAcross[g]}); // by its far corner, as a rule
    }
    for (size_t i = 0; i < mFanSize; ++i) {
        const FanTriangle& f = mFan[i];
        const Vec3d& x = from(i);
        if ((mQ - x).length() > 3 * mBound) // its middle moved a third of that
            mFar.push_back({(x + f.u + f.w) / 3.0, uint32_t(i), f.ids[1]});
        mOld.emplace_back(x, f.u, f.w);
        mOldIds.push_back(f.ids);
        mAfter.push_back({mQ, f.u, f.w, x});
        mNewIds.push_back(f.ids); // v's id stands for q's: only the others are asked
    }
}

bool StepGuard::accepts(const Vec3d& a, const Vec3d& b, const FanTriangle* fan, size_t n,
                        size_t second)
{
    mA = &a, mB = &b, mFan = fan, mFanSize = n, mSecond = second;
    const Vec3d& p = mQ;
    const double bound2 = mBound * mBound;
    if (isFlat()) return true;
    prepare();
    bool nearOld = false;
    const Vec3d* ends[2] = {&a, &b};
    for (int e = 0; e < 2; ++e) // an end that moves less than the bound is near all new
        if ((*ends[e] - p).length() <= mBound)
            nearOld = true;
        else
            mFar.push_back({*ends[e], e == 0 ? 0u : uint32_t(mSecond), kNone}); // its fan first
    for (size_t i = 0; i < mOld.size() && !nearOld; ++i)
        nearOld = mOld[i].within(p, bound2);
    if (!nearOld) return false;
    mNew.clear();
    for (const auto& t : mAfter)
        mNew.emplace_back(t[0], t[1], t[2]);
    if (!nearAll(mFar, mNew, mNewIds, bound2)) return false;
    // and the new surface near the old between the points too: the middles of the new edges
    // out of p (Loop's edge points sit there later). Each is near the old edge it came from
    // when the moving corner moved less than twice the bound.
    mFar.clear();
    for (size_t i = 0; i < mAfter.size(); ++i) // (p, u, w, where p's corner was)
        if ((p - mAfter[i][3]).length() > 2 * mBound)
            mFar.push_back({(p + mAfter[i][1]) * 0.5, uint32_t(i + 2), mNewIds[i][1]});
    return nearAll(mFar, mOld, mOldIds, bound2);
}

/// Whether the collapse moves a flat fan within itself, so that no point need be tested (seven
/// collapses in ten on the 1.7M-particle frames): every corner, p included, lies in a slab no
/// thicker than the bound, every triangle of the old fan and the new faces the slab's normal,
/// and the new fan goes round p once. Then the new fan is a graph over the region its ring
/// bounds in the slab's plane (a simple polygon: star-shaped around p), and so is the old one,
/// whose every triangle faces the normal and whose border is the same ring; each point of
/// either has a point of the other straight above or below it, within the slab.
bool StepGuard::isFlat() const
{
    const Vec3d& p = mQ;
    const Vec3d &a = *mA, &b = *mB;
    Vec3d n(0.0); // the old fan's area-weighted normal
    for (const auto& g : mGone)
        n += g[3];
    for (size_t i = 0; i < mFanSize; ++i)
        n += mFan[i].n0;
    const double len = n.length();
    if (!(len > 0)) return false;
    n /= len;
    for (const auto& g : mGone)
        if (!(g[3].dot(n) > 0)) return false;
    for (size_t i = 0; i < mFanSize; ++i)
        if (!(mFan[i].n0.dot(n) > 0)) return false;
    double lo = 0, hi = (b - a).dot(n);
    if (hi < lo) std::swap(lo, hi);
    auto inSlab = [&](const Vec3d& q) {
        const double d = (q - a).dot(n);
        lo = std::min(lo, d), hi = std::max(hi, d);
        return hi - lo <= mBound;
    };
    if (!inSlab(p)) return false;
    // round p once: the ring's sides that cross a ray from p, in the slab's plane (each
    // crossing counts once in the ring's turning sense, all triangles facing n)
    const Vec3d e = std::abs(n[0]) < 0.9 ? Vec3d(1, 0, 0) : Vec3d(0, 1, 0);
    const Vec3d across = n.cross(e); // the ray runs along n x across, from p
    size_t crossings = 0;
    for (size_t i = 0; i < mFanSize; ++i) { // (p, u, w) with u -> w a side of the ring
        const Vec3d &u = mFan[i].u, &w = mFan[i].w;
        if (!((u - p).cross(w - p).dot(n) > 0) || !inSlab(u) || !inSlab(w)) return false;
        crossings += (u - p).dot(across) < 0 && (w - p).dot(across) >= 0;
    }
    return crossings == 1;
}

/// Each sample within the bound of one of the triangles (ids: their corners).
bool StepGuard::nearAll(const std::vector<Sample>& samples,
                        const std::vector<NearTriangle>& triangles, const std::vector<Ids>& ids,
                        double bound2)
{
    const size_t n = triangles.size();
    for (const Sample& s : samples) {
        auto byHint = [&](size_t i) {
            return s.hint != kNone &&
                   (ids[i][0] == s.hint || ids[i][1] == s.hint || ids[i][2] == s.hint);
        };
        const size_t own = s.own == kNone ? n : s.own;
        bool near = own < n && triangles[own].within(s.q, bound2);
        for (size_t i = 0; i < n && !near; ++i)
            near = i != own && byHint(i) && triangles[i].within(s.q, bound2);
        for (size_t j = 0; j < n && !near; ++j) { // from the own one on, round
            const size_t i = own < n ? (own + 1 + j) % n : j;
            near = i != own && !byHint(i) && triangles[i].within(s.q, bound2);
        }
        if (!near) return false;
    }
    return true;
}

} // namespace post
} // namespace fluidsurf
