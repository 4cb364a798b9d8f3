// CpuBackend.cc - the backend on the CPU (TBB): the stages of neighbors/, classify/, narrowband/
// and field/, in order, each timed in the context.
#include "anisotropy/KernelShapes.h"
#include "backend/Backend.h"
#include "backend/CpuStages.h"
#include "field/AnisotropicField.h"
#include "field/GatherField.h"
#include "mesh/MarchingCubes.h"
#include "narrowband/NarrowBand.h"
#include "util/MarkedNumbers.h"

#include <algorithm>

namespace fluidsurf {
namespace backend {

Classified classifyOnCpu(const Particles& particles, const Params& params, Context& ctx, Band& out,
                         classify::Outputs outputs)
{
    Classified c;
    {
        const auto t = ctx.scope("neighbors");
        const double cellSize = std::min(params.influenceRadius, params.smoothingLength);
        c.index = neighbors::buildCellIndex(
            particles.positions.data(), particles.radii.empty() ? nullptr : particles.radii.data(),
            particles.positions.size(), cellSize, ctx);
    }
    const auto t = ctx.scope("classify");
    c.classes = classify::classifyParticles(c.index, params, ctx, outputs);
    out.interior = c.classes.interior, out.surface = c.classes.surface;
    out.splash = c.classes.splash, out.isolated = c.classes.isolated;
    out.isolatedParticles.clear();
    if (!params.keepIsolated && c.classes.isolated > 0) {
        // found on all threads (a loop over the 13.1M drop's classes took 12 ms on one)
        const auto& classes = c.classes.classes;
        const util::MarkedNumbers isolated(
            classes.size(), [&](size_t i) { return classes[i] == classify::Isolated; });
        out.isolatedParticles.resize(isolated.count());
        isolated.forEach([&](size_t i, bool marked, size_t k) {
            if (marked) out.isolatedParticles[k - 1] = c.index.order[i];
        });
    }
    std::sort(out.isolatedParticles.begin(), out.isolatedParticles.end());
    return c;
}

neighbors::CellIndex fieldParticles(Classified&& c, const Params& params)
{
    if (c.classes.isolated && !params.keepIsolated) {
        // in place: no second index
        neighbors::keepParticles(c.index, classify::notIsolated(c.classes));
    }
    neighbors::CellIndex out = std::move(c.index);
    c = Classified(); // the classes, held through the field otherwise
    return out;
}

void narrowBandOnCpu(const Classified& c, const Params& params, const Level& level, double width,
                     Context& ctx, Band& out)
{
    const auto t = ctx.scope("narrow band");
    const openvdb::MaskTree::Ptr band =
        narrowband::buildNarrowBand(c.index, c.classes, params, level, width, ctx);
    out.tree = std::make_shared<openvdb::FloatTree>(*band, float(params.background(level)),
                                                    openvdb::TopologyCopy());
}

std::unique_ptr<AnisotropicStage> anisotropicStage(Classified&& c, const Params& params,
                                                   Context& ctx)
{
    const auto t = ctx.scope("kernel shapes");
    const anisotropy::ShapeParams sp = anisotropy::shapeParams(params);
    auto stage = std::make_unique<AnisotropicStage>();
    {
        const anisotropy::KernelShapes shapes =
            anisotropy::kernelShapes(c.index, c.classes, sp, ctx);
        if (sp.centreSmoothing == 0) { // the centres are the particles: their index serves
            const classify::Classification classes = std::move(c.classes);
            stage->kernels = anisotropy::kernelParticles(std::move(c.index), classes, shapes,
                                                         params.keepIsolated);
        } else {
            stage->kernels = anisotropy::kernelParticles(
                c.index, c.classes, shapes, params.keepIsolated, params.influenceRadius, ctx);
        }
        c = Classified();
    }
    stage->table =
        field::anisotropicKernels(stage->kernels.centres, stage->kernels.shapes.data(),
                                  anisotropy::maxReach(sp) * params.influenceRadius, params);
    stage->kernels.shapes = {}; // (the table holds what the gather needs)
    return stage;
}

namespace {

class CpuBackend : public Backend
{
public:
    std::string name() const override { return "cpu"; }

    bool narrowBand(const Particles& particles, const Params& params, const Level& level,
                    double width, Context& ctx, Band& out, std::string& /*whyNot*/) override
    {
        // the classes alone: the band and the field's particles need nothing else
        Classified c = classifyOnCpu(particles, params, ctx, out);
        narrowBandOnCpu(c, params, level, width, ctx, out);
        if (isAnisotropic(params.field)) {
            mAniso = anisotropicStage(std::move(c), params, ctx);
            const auto t = ctx.scope("field");
            mParticles = nullptr;
            out.evaluations = evaluate(*out.tree, params, level, ctx);
            return true;
        }
        const auto t = ctx.scope("field");
        mOwned = fieldParticles(std::move(c), params);
        mParticles = &mOwned;
        out.evaluations = field::evaluateField(*out.tree, mOwned, params, level, ctx);
        return true;
    }

    void useParticles(const neighbors::CellIndex& particles) override { mParticles = &particles; }

    size_t evaluate(openvdb::FloatTree& tree, const Params& params, const Level& level,
                    Context& ctx) override
    {
        if (isAnisotropic(params.field)) { // (narrowBand made the kernels)
            if (!mAniso) throw Error("CPU backend: evaluate() before the kernels were made");
            return field::evaluateAnisotropicField(tree, mAniso->table, params, level, ctx);
        }
        if (!mParticles) throw Error("CPU backend: evaluate() before the particles were given");
        return field::evaluateField(tree, *mParticles, params, level, ctx);
    }

    bool marchingCubes(const openvdb::FloatGrid& grid, RawNormals normals, Context& ctx,
                       TriangleMesh& out, size_t& cells) override
    {
        out = mesh::marchingCubes(grid, ctx, &cells, normals);
        return true;
    }

    void smoothMesh(TriangleMesh& mesh, const post::SmoothParams& params, Context&) override
    {
        mesh = post::smoothAlongNormals(std::move(mesh), params);
    }

    std::vector<uint32_t> componentsOfParticles(const TriangleMesh& mesh,
                                                const std::vector<uint32_t>& ofPoint,
                                                const post::Components& c,
                                                const ParticleVolumes& particles, double cellSize,
                                                Context&) override
    {
        return post::componentsOfParticles(mesh, ofPoint, c, particles, cellSize);
    }

private:
    neighbors::CellIndex mOwned;
    const neighbors::CellIndex* mParticles = nullptr;
    std::unique_ptr<AnisotropicStage> mAniso; ///< Ssp07Aniso: the kernels
};

} // namespace

std::unique_ptr<Backend> makeCpuBackend()
{
    return std::make_unique<CpuBackend>();
}

} // namespace backend
} // namespace fluidsurf
