// CpuStages.h - the CPU's first stages (neighbors, classify, dropping isolated particles), shared
// by the CPU backend's narrow band and the thesis' baselines (gather-full, scatter), which index
// and classify on the CPU whatever the backend.
#pragma once

#include "backend/Backend.h"
#include "classify/Classify.h"
#include "neighbors/CellIndex.h"

namespace fluidsurf {
namespace backend {

struct Classified
{
    neighbors::CellIndex index;
    classify::Classification classes;
};

/// "neighbors" and "classify" (timed in ctx); class counts and the isolated particles (input
/// indices, ascending, unless kept) go into out. `outputs`: what the classification holds
/// besides the classes.
Classified classifyOnCpu(const Particles& particles, const Params& params, Context& ctx, Band& out,
                         classify::Outputs outputs = {});

/// The index without its isolated particles (they take no part in the field), unless kept.
/// c is left empty: its index and classes are given back before the field is evaluated.
neighbors::CellIndex fieldParticles(Classified&& c, const Params& params);

} // namespace backend
} // namespace fluidsurf
