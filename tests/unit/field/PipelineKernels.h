// PipelineKernels.h - the anisotropic kernels' table as the CPU pipeline makes it (index,
// classes, shapes, kernel particles, table), for the tests of what reads the table.
#pragma once

#include "anisotropy/KernelShapes.h"
#include "classify/Classify.h"
#include "field/AnisotropicField.h"

#include <fluidsurf/ParticleSet.h>

#include <algorithm>
#include <memory>

namespace fluidsurf {
namespace testing_support {

struct PipelineKernels
{
    anisotropy::KernelShapes shapes;
    anisotropy::KernelParticles particles;
    field::AnisotropicKernels table; ///< (points into particles.centres: the object stays put)
};

inline std::unique_ptr<PipelineKernels> pipelineKernels(const ParticleSet& ps, const Params& p,
                                                        Context& ctx)
{
    const double cellSize = std::min(p.influenceRadius, p.smoothingLength);
    const neighbors::CellIndex index =
        neighbors::buildCellIndex(ps.positions.data(), nullptr, ps.size(), cellSize, ctx);
    const classify::Classification classes = classify::classifyParticles(index, p, ctx);
    const anisotropy::ShapeParams shapeParams = anisotropy::shapeParams(p);
    auto k = std::make_unique<PipelineKernels>();
    k->shapes = anisotropy::kernelShapes(index, classes, shapeParams, ctx);
    k->particles = anisotropy::kernelParticles(index, classes, k->shapes, p.keepIsolated,
                                               p.influenceRadius, ctx);
    k->table = field::anisotropicKernels(k->particles.centres, k->particles.shapes.data(),
                                         anisotropy::maxReach(shapeParams) * p.influenceRadius, p);
    return k;
}

} // namespace testing_support
} // namespace fluidsurf
