// StepGuard.h - decimation's guard on how far one collapse moves the surface
// (DecimateTarget::maxStep), both ways: the new point near the old fan; the old ends and the old
// triangles' middles (standing for the surface they covered) near the new fan; and the middles
// of the new edges out of the new point near the old fan. The last is what catches a collapse
// across a ridge or a sheet's rim, which cuts it between the points (by 0.56 voxel on the
// 1.7M-particle frame at t = 0.5 s, where every point stayed within 0.4); the new triangles'
// middles refused nothing more once the edges' were checked.
//
// Points are sampled, not surfaces compared: a bound per collapse, not a proof for the whole
// decimation (collapses build on each other; PostProcess.cc says what the chain keeps).
#pragma once

#include "util/TriangleDistance.h"
#include "util/Vec3d.h"

#include <array>
#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace post {

/// A triangle of a collapse's fans that stays, as the decimation's guards see it: (v, u, w) in
/// its own turning order, the corner v moving from its end's point x to q (x is the end's, so
/// not kept here); n0 = (u - x) x (w - x), found once for all the guards. `t` is the caller's.
struct FanTriangle
{
    uint32_t t;
    std::array<uint32_t, 3> ids;
    Vec3d u, w, n0;
};

/// The two fans of one collapse: start() with the two triangles that go (in their own order,
/// with their normals and the corners across the edge), then accepts() with the rest, which
/// it reads where the caller keeps them. Vertex ids are the caller's, used only to say which
/// triangles share a corner.
class StepGuard
{
public:
    using Ids = std::array<uint32_t, 3>;

    explicit StepGuard(double bound) : mBound(bound) {}

    /// A collapse of an edge to the point q; gone[g] = (x, u, w, n = (u - x) x (w - x)) for the
    /// two triangles that go, ids their corners, across their corners across the edge.
    void start(const Vec3d& q, const std::array<Vec3d, 4> (&gone)[2], const Ids (&ids)[2],
               const uint32_t (&across)[2], const Vec3d (&acrossPoints)[2]);
    /// Whether every sample of either fan lies within the bound of the other. a and b are the
    /// edge's ends; fan[0, second) moves a's corner, fan[second, n) b's.
    bool accepts(const Vec3d& a, const Vec3d& b, const FanTriangle* fan, size_t n, size_t second);

private:
    /// A point to find near a fan: the triangle to try first (kNone: none) and a ring vertex
    /// it lies by (kNone: none), whose triangles come next.
    struct Sample
    {
        Vec3d q;
        uint32_t own, hint;
    };
    static constexpr uint32_t kNone = UINT32_MAX;

    /// The moved corner's old point of fan triangle i.
    const Vec3d& from(size_t i) const { return i < mSecond ? *mA : *mB; }
    bool isFlat() const;
    /// Seven collapses in ten end at isFlat, which needs only the normals and points: the
    /// samples are found only here.
    void prepare();

    /// The two fans, as nearAll asks them: the old one (the two that go first, then the
    /// caller's fan where it was) and the new one (the caller's fan with q for its moved
    /// corner). A triangle is set up for point questions (NearTriangle) when first asked: a
    /// sample is found by its own triangle or a neighbour of it as a rule, and most of a fan
    /// is never asked.
    enum class Fan { Old, New };
    size_t size(Fan f) const { return f == Fan::Old ? mFanSize + 2 : mFanSize; }
    /// Corners' ids (a moved corner keeps its id in the new fan).
    const Ids& ids(Fan f, size_t i) const;
    const NearTriangle& triangle(Fan f, size_t i);
    bool nearAll(const std::vector<Sample>& samples, Fan f, double bound2);

    double mBound;
    Vec3d mQ{0.0};
    std::array<Vec3d, 4> mGone[2]{}; ///< (x, u, w, normal) of the two that go
    Ids mGoneIds[2]{};
    uint32_t mAcross[2] = {kNone, kNone};
    Vec3d mAcrossPoint[2] = {Vec3d(0.0), Vec3d(0.0)};
    const Vec3d *mA = nullptr, *mB = nullptr; ///< the ends' old points (accepts)
    const FanTriangle* mFan = nullptr;        ///< the rest, the caller's (accepts)
    size_t mFanSize = 0, mSecond = 0;

    /// The fans' triangles as set up so far (`mReady`: which), by the indices above; the
    /// arrays only grow (NearTriangle's construction is the work put off).
    std::vector<NearTriangle> mOld, mNew;
    std::vector<uint8_t> mReady[2];
    std::vector<Sample> mFar; ///< points to find near a fan
};

} // namespace post
} // namespace fluidsurf
