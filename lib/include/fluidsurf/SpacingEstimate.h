// SpacingEstimate.h - estimate the particle spacing of a frame, and the radius r it implies
// (r = spacing / 2, DESIGN.md). On ordered particles (a lattice) and flat layers the spacing is
// the median distance to the nearest neighbour. Disordered SPH particles pair up, so that
// distance runs 15-25% under the rest spacing on DualSPHysics frames and 5-30% under on
// SPlisHSPlasH's: there the spacing comes from the particles' SPH density (one particle per
// spacing cubed in the bulk), which the simulators hold at rest: within 0.5% of the given
// radius on the DualSPHysics frames of ../shared/data, within 2-7% on SPlisHSPlasH's (whose
// nearest-neighbour halves were 15-25% and 5-28% short). Frames without a bulk (scattered or
// random points, shells, thin sheets) keep the nearest-neighbour spacing. Still an estimate:
// prefer the simulator's radius when known, and print an estimate as an estimate.
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/ParticleSet.h>

namespace fluidsurf {

struct SpacingEstimate
{
    double medianNearest = 0; ///< median nearest-neighbour distance, world units (0: unknown)
    double spacing = 0;       ///< the estimated rest spacing (see above), world units
    bool fromDensity = false; ///< spacing from the density, not from medianNearest
    double radius = 0;        ///< implied particle radius r = spacing / 2
    size_t sampled = 0;       ///< particles whose nearest neighbour was measured
    size_t isolated = 0;      ///< sampled particles with no neighbour in reach
};

/// Exact nearest neighbours for up to maxSamples evenly spaced particles (all if fewer); the
/// density (where used) of 20,000 of them. A cell of the search holding more than a few
/// thousand particles (a pile of coincident or near-coincident ones, or cells made huge by a far
/// outlier) is sorted along its widest axis for the nearest-neighbour queries (still exact) and
/// sampled evenly for the density sums, so that 200,000 particles at one point no longer take
/// minutes. ctx's checkpoint is called once per range of queries (a cancel throws Cancelled).
SpacingEstimate estimateSpacing(const ParticleSet& particles, Context& ctx,
                                size_t maxSamples = 200000);
/// The same with a context of its own (no progress, no cancel).
SpacingEstimate estimateSpacing(const ParticleSet& particles, size_t maxSamples = 200000);

} // namespace fluidsurf
