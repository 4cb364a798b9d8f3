// GradientMath.h - one axis of the field gradient at a grid point (thesis eq. 4.10-4.12: central
// differences, one-sided where a neighbour is outside the band), as plain math that the CPU
// mesher (mesh/Gradient.h) and the GPU one (cuda/src/MarchingCubes.cu) both compile, so that
// their vertex normals agree to the bit.
#pragma once

#include "util/HostDevice.h"

namespace fluidsurf {
namespace mesh {

/// d phi / d axis (index space) from the neighbours below (lo) and above (hi) along the axis,
/// each with whether it is active, and the point's own value.
FLUIDSURF_HD inline double centralDifference(bool onLo, float lo, bool onHi, float hi, float center)
{
    if (onLo && onHi) return 0.5 * (double(hi) - double(lo));
    if (onHi) return double(hi) - double(center);
    if (onLo) return double(center) - double(lo);
    return 0.0;
}

} // namespace mesh
} // namespace fluidsurf
