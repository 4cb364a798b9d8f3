// StepGuard.cc - how far one collapse moves the surface (see StepGuard.h).
//
// A flat fan is let through without a point tested (isFlat), from the normals the caller has
// found already and the fans where the caller keeps them. Only otherwise are the fans'
// triangles set up (NearTriangle), each as the questions reach it, and each point is tried
// first against the triangle it came from and those by its ring vertex, where it lies as a rule.
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
    mFar.clear();
    for (int f = 0; f < 2; ++f) { // nothing set up yet
        const size_t n = size(Fan(f));
        mReady[f].assign(n, 0);
        std::vector<NearTriangle>& t = f == 0 ? mOld : mNew;
        if (t.size() < n) t.resize(n);
    }
    for (int g = 0; g < 2; ++g) {
        const auto& [x, u, w, n] = mGone[g];
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
    }
}

const StepGuard::Ids& StepGuard::ids(Fan f, size_t i) const
{
    if (f == Fan::Old) return i < 2 ? mGoneIds[i] : mFan[i - 2].ids;
    return mFan[i].ids; // v's id stands for q's: only the others are asked
}

const NearTriangle& StepGuard::triangle(Fan f, size_t i)
{
    const bool old = f == Fan::Old;
    NearTriangle& t = (old ? mOld : mNew)[i];
    if (!mReady[old ? 0 : 1][i]) {
        mReady[old ? 0 : 1][i] = 1;
        if (!old)
            t = NearTriangle(mQ, mFan[i].u, mFan[i].w);
        else if (i < 2)
            t = NearTriangle(mGone[i][0], mGone[i][1], mGone[i][2]);
        else
            t = NearTriangle(from(i - 2), mFan[i - 2].u, mFan[i - 2].w);
    }
    return t;
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
    for (size_t i = 0; i < size(Fan::Old) && !nearOld; ++i)
        nearOld = triangle(Fan::Old, i).within(p, bound2);
    if (!nearOld) return false;
    if (!nearAll(mFar, Fan::New, bound2)) return false;
    // and the new surface near the old between the points too: the middles of the new edges
    // out of p (Loop's edge points sit there later). Each is near the old edge it came from
    // when the moving corner moved less than twice the bound.
    mFar.clear();
    for (size_t i = 0; i < mFanSize; ++i) // (p, u, w), p's corner from from(i)
        if ((p - from(i)).length() > 2 * mBound)
            mFar.push_back({(p + mFan[i].u) * 0.5, uint32_t(i + 2), mFan[i].ids[1]});
    return nearAll(mFar, Fan::Old, bound2);
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

/// Each sample within the bound of one of fan f's triangles.
bool StepGuard::nearAll(const std::vector<Sample>& samples, Fan f, double bound2)
{
    const size_t n = size(f);
    for (const Sample& s : samples) {
        auto byHint = [&](size_t i) {
            const Ids& c = ids(f, i);
            return s.hint != kNone && (c[0] == s.hint || c[1] == s.hint || c[2] == s.hint);
        };
        const size_t own = s.own == kNone ? n : s.own;
        bool near = own < n && triangle(f, own).within(s.q, bound2);
        for (size_t i = 0; i < n && !near; ++i)
            near = i != own && byHint(i) && triangle(f, i).within(s.q, bound2);
        for (size_t j = 0; j < n && !near; ++j) { // from the own one on, round
            const size_t i = own < n ? (own + 1 + j) % n : j;
            near = i != own && !byHint(i) && triangle(f, i).within(s.q, bound2);
        }
        if (!near) return false;
    }
    return true;
}

} // namespace post
} // namespace fluidsurf
