// Level.h - the grid geometry a stage works on (DESIGN.md, "Contexts and levels"): stages take a
// Level instead of reading Params::voxelSize, so the same stage can run at 4r, 2r and r within
// one reconstruction (the adaptive grid of thesis chapter 6). Voxel (i,j,k) sits at
// (i,j,k) * voxelSize in world units.
#pragma once

#include <openvdb/math/Transform.h>

namespace fluidsurf {

struct Level
{
    double voxelSize = 0; ///< dx, world units

    /// The linear transform of a grid at this level.
    openvdb::math::Transform::Ptr transform() const
    {
        return openvdb::math::Transform::createLinearTransform(voxelSize);
    }
};

} // namespace fluidsurf
