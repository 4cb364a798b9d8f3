// SpacingEstimate.h - estimate the particle spacing of a frame from the median distance to the
// nearest neighbour, and the radius r it implies (r = spacing / 2, DESIGN.md). Disordered SPH
// particles pair up, so this underestimates the rest spacing (by ~20% on DualSPHysics frames):
// prefer the simulator's radius when known, and print an estimate as an estimate.
#pragma once

#include <fluidsurf/ParticleSet.h>

namespace fluidsurf {

struct SpacingEstimate
{
    double medianNearest = 0; ///< median nearest-neighbour distance, world units (0: unknown)
    double radius = 0;        ///< implied particle radius r = medianNearest / 2
    size_t sampled = 0;       ///< particles whose nearest neighbour was measured
    size_t isolated = 0;      ///< sampled particles with no neighbour in reach
};

/// Exact nearest neighbours for up to maxSamples evenly spaced particles (all if fewer).
SpacingEstimate estimateSpacing(const ParticleSet& particles, size_t maxSamples = 200000);

} // namespace fluidsurf
