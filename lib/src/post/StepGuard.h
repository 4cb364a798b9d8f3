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

/// The two fans of one collapse, filled in this order: start(), the two triangles that go
/// (addGone), the remaining triangles of one end's fan (addMoved), startSecondFan(), those of
/// the other's; then accepts(). Vertex ids are the caller's, used only to say which
/// triangles share a corner.
class StepGuard
{
public:
    using Ids = std::array<uint32_t, 3>;

    explicit StepGuard(double bound) : mBound(bound) {}

    /// A collapse of an edge to the point q.
    void start(const Vec3d& q);
    /// One of the two triangles that go (in its own order), and its corner across the edge.
    void addGone(const Ids& ids, const Vec3d& x, const Vec3d& u, const Vec3d& w, uint32_t across,
                 const Vec3d& acrossPoint);
    void startSecondFan() { mSecond = uint32_t(mAfter.size()); }
    /// A remaining triangle (v, u, w) in its own turning order, v moving from x to q.
    void addMoved(const Ids& ids, const Vec3d& x, const Vec3d& u, const Vec3d& w);
    /// Whether every sample of either fan lies within the bound of the other; a and b the
    /// edge's ends (the first fan's and the second's).
    bool accepts(const Vec3d& a, const Vec3d& b);

private:
    /// A point to find near a fan: the triangle to try first (kNone: none) and a ring vertex
    /// it lies by (kNone: none), whose triangles come next.
    struct Sample
    {
        Vec3d q;
        uint32_t own, hint;
    };
    static constexpr uint32_t kNone = UINT32_MAX;

    bool isFlat(const Vec3d& a, const Vec3d& b) const;
    static bool nearAll(const std::vector<Sample>& samples,
                        const std::vector<NearTriangle>& triangles, const std::vector<Ids>& ids,
                        double bound2);

    double mBound;
    Vec3d mQ{0.0};
    std::vector<NearTriangle> mOld, mNew;     ///< the old fan (the two that go first), the new
    std::vector<Ids> mOldIds, mNewIds;        ///< their corners (a moved corner keeps its id)
    std::vector<std::array<Vec3d, 4>> mAfter; ///< the new fan (q, u, w), and where q's corner was;
                                              ///< mAfter[i] is mOld[i + 2] moved
    std::vector<Sample> mFar;                 ///< old points to find near the new fan
    uint32_t mSecond = 0;                     ///< mAfter's triangles of the second fan start here
};

} // namespace post
} // namespace fluidsurf
