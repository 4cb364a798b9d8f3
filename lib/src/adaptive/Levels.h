// Levels.h - the index space shared by the adaptive grid's levels (fluidsurf/AdaptiveGrid.h) and
// the one rule that says which level-3 values are sub-sampled, used by the stage that fills the
// grids (LevelFields) and by the mesher (MeshLevels), which must agree on it exactly.
//
// All coordinates here are level-3 indices (spacing dx) unless named otherwise: a level-2 index
// is half of one (even coordinates only), a coarse cell index a quarter (floor).
#pragma once

#include <openvdb/openvdb.h>

namespace fluidsurf {
namespace adaptive {

using openvdb::Coord;
using LevelTree = openvdb::Int32Tree;
constexpr int kLevel2 = 2, kLevel3 = 3;

/// The coarse cell holding level-3 point p in its interior or on its lower faces.
inline Coord coarseCell(const Coord& p)
{
    return Coord(p.x() >> 2, p.y() >> 2, p.z() >> 2);
}

/// The value at the middle of a level-2 edge with end values a and b, and at the centre of a
/// level-2 face with corners a, b, c, d (any order of the same four numbers gives the same
/// float: (a + c) and (b + d) are summed first, opposite corners). Linear and bilinear
/// interpolation; the mesher recomputes midValue to find the half of a level-2 edge its
/// crossing lies on, so this is the only place the rounding is written down.
inline float midValue(float a, float b)
{
    return 0.5f * (a + b);
}
inline float centreValue(float a, float b, float c, float d)
{
    return 0.25f * ((a + c) + (b + d));
}

/// Levels of the coarse cells, read through a cached accessor (0: not meshed).
class LevelLookup
{
public:
    explicit LevelLookup(const LevelTree& tree) : mAcc(tree) {}

    int level(const Coord& cell)
    {
        int v = 0;
        return mAcc.probeValue(cell, v) ? v : 0;
    }

    /// Whether level-3 point p lies on the closed box of a level-2 cell: its value there is
    /// sub-sampled from level 2. Only points with an odd coordinate can be (even points are
    /// level-2 points), and only those on a coarse face or edge.
    bool subsampled(const Coord& p) { return ((p.x() | p.y() | p.z()) & 1) && touches(p, kLevel2); }

    /// Whether level-3 point p lies on the closed box of a coarse cell at the level.
    bool touches(const Coord& p, int at)
    {
        int lo[3], hi[3];
        for (int a = 0; a < 3; ++a) {
            hi[a] = p[a] >> 2;
            lo[a] = (p[a] & 3) == 0 ? hi[a] - 1 : hi[a];
        }
        for (int z = lo[2]; z <= hi[2]; ++z)
            for (int y = lo[1]; y <= hi[1]; ++y)
                for (int x = lo[0]; x <= hi[0]; ++x)
                    if (level(Coord(x, y, z)) == at) return true;
        return false;
    }

private:
    openvdb::tree::ValueAccessor<const LevelTree> mAcc;
};

} // namespace adaptive
} // namespace fluidsurf
