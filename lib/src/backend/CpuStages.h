// CpuStages.h - the CPU's first stages (neighbors, classify, dropping isolated particles), shared
// by the CPU backend's narrow band and the thesis' baselines (gather-full, scatter), which index
// and classify on the CPU whatever the backend.
#pragma once

#include "anisotropy/KernelShapes.h"
#include "backend/Backend.h"
#include "classify/Classify.h"
#include "field/AnisotropicField.h"
#include "neighbors/CellIndex.h"

#include <memory>

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

/// "narrow band": the band's topology from the classes (thesis §4.2.1) into out.tree, every
/// active voxel at the background until the field fills it.
void narrowBandOnCpu(const Classified& c, const Params& params, const Level& level, double width,
                     Context& ctx, Band& out);

/// The ssp07-aniso field's kernels ("kernel shapes"): their shapes, their centres indexed anew
/// and what the gather needs of each. Made in place and never moved (table points at
/// kernels.centres); both backends gather from it, the CUDA one after uploading it.
struct AnisotropicStage
{
    anisotropy::KernelParticles kernels;
    field::AnisotropicKernels table;
};
/// c is left empty: with lambda = 0 its index becomes the kernels' (fieldParticles).
std::unique_ptr<AnisotropicStage> anisotropicStage(Classified&& c, const Params& params,
                                                   Context& ctx);

} // namespace backend
} // namespace fluidsurf
