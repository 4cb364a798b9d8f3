// Rasterize.cc - the rasterize pipeline: checks the input, picks the backend, and runs the
// stages in order through the context (timing scopes, checkpoints, thread limit).
#include <fluidsurf/Error.h>
#include <fluidsurf/Rasterize.h>

#include "adaptive/Curvature.h"
#include "adaptive/LevelFields.h"
#include "adaptive/LevelMap.h"
#include "backend/Backend.h"
#include "backend/CpuStages.h"
#include "field/CompleteBand.h"
#include "field/ScatterField.h"
#include "levelset/LevelSet.h"
#include "narrowband/NarrowBand.h"
#include "neighbors/FarParticles.h"
#include "util/Threads.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <future>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

namespace fluidsurf {

namespace {

/// Per-particle radii from the radius attribute, or empty for the uniform radius.
std::vector<float> particleRadii(const ParticleSet& ps, const Params& params)
{
    const Attribute* a = params.perParticleRadii ? ps.find(AttributeRole::Radius) : nullptr;
    if (!a) return {};
    // A radius far past the frame's r makes one particle's kernel cover the whole frame: one
    // pscale of 1e30 emptied the mesh. Past kRadiusRatio r it is an error in the data.
    constexpr double kRadiusRatio = 1000;
    const double limit = std::min(kMaxCoordinate, kRadiusRatio * params.radius);
    for (size_t i = 0; i < a->floats.size(); ++i)
        if (!(a->floats[i] > 0) || !(a->floats[i] <= limit)) {
            char text[300];
            std::snprintf(text, sizeof(text),
                          "radius attribute '%s' of particle %zu is %g; radii must be positive "
                          "and at most %g (%g r, r = %g) (or ignore the attribute)",
                          a->name.c_str(), i, double(a->floats[i]), limit, kRadiusRatio,
                          params.radius);
            throw ValueError(text);
        }
    return a->floats;
}

struct Run
{
    const backend::Particles& particles;
    const Params& params;
    const Level& level;
    Context& ctx;
    RasterizeResult& result;
    float maxRadius;

    /// The band with phi, completed where a zero crossing reaches its edge (thesis ch. 4).
    openvdb::FloatTree::Ptr narrowBand(backend::Backend& b)
    {
        RasterizeStats& stats = result.stats;
        backend::Band band;
        std::unique_ptr<backend::Backend> cpu;
        backend::Backend* on = &b;
        if (std::string whyNot;
            !b.narrowBand(particles, params, level, stats.bandWidth, ctx, band, whyNot)) {
            cpu = backend::makeCpuBackend();
            on = cpu.get();
            stats.device = "cpu (" + whyNot + ")";
            on->narrowBand(particles, params, level, stats.bandWidth, ctx, band, whyNot);
        }
        take(band);
        const auto t = ctx.scope("complete band");
        stats.bandCompletion = field::completeBand(
            *band.tree, level,
            [&](openvdb::FloatTree& grown) { on->evaluate(grown, params, level, ctx); }, ctx);
        stats.fieldEvaluations += stats.bandCompletion;
        return band.tree;
    }

    /// The thesis' baselines: indexed and classified on the CPU, then every vertex of the
    /// bounding volume evaluated by the backend (gather-full) or the serial scatter.
    openvdb::FloatTree::Ptr baseline(backend::Backend& b)
    {
        RasterizeStats& stats = result.stats;
        backend::Band band;
        neighbors::CellIndex index =
            backend::fieldParticles(backend::classifyOnCpu(particles, params, ctx, band), params);
        take(band);
        if (params.method == FieldMethod::Scatter) {
            const auto t = ctx.scope("field");
            return field::scatterField(index, params, level, ctx, &stats.fieldEvaluations);
        }
        auto tree = std::make_shared<openvdb::FloatTree>(float(params.background(level)));
        {
            const auto t = ctx.scope("bounding volume");
            const openvdb::CoordBBox box = narrowband::boundingVolume(index, params, level);
            if (!box.empty()) {
                narrowband::checkDenseMemory(box, sizeof(float) * 1.2, "gather-full");
                tree->denseFill(box, float(params.background(level)), true);
            }
        }
        const auto t = ctx.scope("field");
        b.useParticles(index);
        stats.fieldEvaluations = b.evaluate(*tree, params, level, ctx);
        return tree;
    }

    /// The 3-level grid (thesis ch. 6): classified on the CPU (the curvature needs the classes),
    /// the level-2 band at 2 dx evaluated by the backend, the level map, then the points each
    /// level needs (adaptive/), whose completion replaces the band's. Returns the level-3 tree;
    /// level2 is set.
    openvdb::FloatTree::Ptr adaptive(backend::Backend& b, openvdb::FloatTree::Ptr& level2,
                                     adaptive::LevelTree::Ptr& levels)
    {
        RasterizeStats& stats = result.stats;
        backend::Band band;
        // the sums for the neighbour counts (the level map), the normals for the curvature
        backend::Classified c =
            backend::classifyOnCpu(particles, params, ctx, band, classify::Outputs{true, true});
        take(band);
        std::vector<float> kappa;
        {
            const auto t = ctx.scope("curvature");
            kappa = adaptive::particleCurvature(c.index, c.classes, params, ctx);
        }
        // Only the classes and neighbour counts go on (to the band and the level map).
        std::vector<Vec3f>().swap(c.classes.normals);
        decltype(c.classes.colorField)().swap(c.classes.colorField);
        decltype(c.classes.colorGradient)().swap(c.classes.colorGradient);
        // The field's particles: the index without its isolated ones, which the band and the
        // level map pass over too. The classes and kappa follow it, and the full index goes
        // before the band is built.
        if (c.classes.isolated && !params.keepIsolated) {
            const std::vector<uint8_t> keep = classify::notIsolated(c.classes);
            neighbors::keepParticles(c.index, keep);
            classify::selectClasses(c.classes, keep);
            classify::selectInPlace(kappa, keep);
        }
        b.useParticles(c.index);
        const Level mid{2 * level.voxelSize};
        {
            const auto t = ctx.scope("narrow band");
            const double width = narrowband::effectiveBandWidth(params, mid, maxRadius);
            const openvdb::MaskTree::Ptr mask =
                narrowband::buildNarrowBand(c.index, c.classes, params, mid, width, ctx);
            level2 = std::make_shared<openvdb::FloatTree>(*mask, float(params.background(mid)),
                                                          openvdb::TopologyCopy());
        }
        const field::FieldEvaluator evaluate2 = [&](openvdb::FloatTree& t) {
            stats.fieldEvaluations += b.evaluate(t, params, mid, ctx);
        };
        const field::FieldEvaluator evaluate3 = [&](openvdb::FloatTree& t) {
            stats.fieldEvaluations += b.evaluate(t, params, level, ctx);
        };
        {
            const auto t = ctx.scope("field");
            evaluate2(*level2);
        }
        {
            const auto t = ctx.scope("level map");
            levels = adaptive::buildLevelMap(
                {*level2, c.index, c.classes, kappa, level.voxelSize, stats.bandWidth,
                 params.curvatureThreshold,
                 uint32_t(std::max(params.thinNeighbours, params.splashNeighbours))},
                ctx);
        }
        // The classes, normals and curvature have done their work: their memory (~30 bytes a
        // particle) is given back before the level fields, the peak of this path.
        c.classes = classify::Classification();
        std::vector<float>().swap(kappa);
        const auto t = ctx.scope("level fields");
        adaptive::LevelFieldStats f;
        openvdb::FloatTree::Ptr level3 = adaptive::fillLevels(
            *level2, *levels, evaluate2, evaluate3, float(params.background(level)),
            adaptive::Refinement{float(params.levelTolerance * level.voxelSize)}, ctx, &f);
        stats.completionCells = f.completionCells, stats.subsampled = f.subsampled;
        stats.refinedCells = f.refinedCells;
        stats.islandCells = f.islandCells;
        stats.level2CrossingProbes = f.crossingProbes;
        for (auto v = levels->cbeginValueOn(); v; ++v)
            (*v == adaptive::kLevel3 ? stats.level3Cells : stats.level2Cells) += 1;
        return level3;
    }

    void take(backend::Band& band)
    {
        RasterizeStats& stats = result.stats;
        stats.interior = band.interior, stats.surface = band.surface;
        stats.splash = band.splash, stats.isolated = band.isolated;
        stats.fieldEvaluations = band.evaluations;
        result.isolatedParticles = std::move(band.isolatedParticles);
    }
};

RasterizeResult rasterize(const ParticleSet& ps, const Params& params, Context& ctx,
                          const std::string& source)
{
    const auto timer = ctx.scope("rasterize");
    // Looking for the GPU (and creating its context, unless prepareDevice did earlier) runs on
    // a thread while the radii are checked.
    struct GpuCheck
    {
        bool usable = false;
        std::string reason;
    };
    const Device device = params.method == FieldMethod::Scatter ? Device::Cpu : ctx.device();
    std::future<GpuCheck> gpuCheck;
    if (device != Device::Cpu)
        gpuCheck = std::async(std::launch::async, [] {
            GpuCheck c;
            c.usable = backend::cudaUsable(&c.reason);
            return c;
        });
    RasterizeResult result;
    RasterizeStats& stats = result.stats;
    stats.particles = ps.size();
    const Level level = params.level();
    const std::vector<float> radii = particleRadii(ps, params);
    float maxRadius = float(params.radius);
    for (float r : radii)
        maxRadius = std::max(maxRadius, r);
    stats.bandWidth = narrowband::effectiveBandWidth(params, level, maxRadius);
    GpuCheck gpu;
    if (gpuCheck.valid()) {
        const auto t = ctx.scope("cuda context"); // waiting for it, unless made earlier
        gpu = gpuCheck.get();
    }

    // A stray particle beyond the cell grid's reach is isolated by definition: it is taken out
    // before the stages and reported with the others. Frames within reach are not touched.
    std::vector<uint32_t> far, kept;
    std::vector<Vec3f> keptPositions;
    std::vector<float> keptRadii;
    const double cellSize = std::min(params.influenceRadius, params.smoothingLength);
    if (!params.keepIsolated && neighbors::exceedsCellRange(ps.positions, cellSize)) {
        far = neighbors::axisSingletons(ps.positions,
                                        std::max(params.influenceRadius, params.smoothingLength));
        std::vector<uint8_t> isFar(ps.size(), 0);
        for (uint32_t i : far)
            isFar[i] = 1;
        for (uint32_t i = 0; i < ps.size(); ++i)
            if (!isFar[i]) {
                kept.push_back(i), keptPositions.push_back(ps.positions[i]);
                if (!radii.empty()) keptRadii.push_back(radii[i]);
            }
    }
    const bool reduced = !far.empty();
    const backend::Particles particles{reduced ? keptPositions : ps.positions,
                                       reduced ? keptRadii : radii};
    openvdb::FloatTree::Ptr tree, fine;
    adaptive::LevelTree::Ptr levels;
    backend::runOn(device, gpu.usable, gpu.reason, stats, [&](backend::Backend& b) {
        Run run{particles, params, level, ctx, result, maxRadius};
        if (params.adaptive)
            fine = run.adaptive(b, tree, levels);
        else
            tree = params.method == FieldMethod::NarrowBand ? run.narrowBand(b) : run.baseline(b);
    });
    if (reduced) {
        for (uint32_t& i : result.isolatedParticles)
            i = kept[i];
        result.isolatedParticles.insert(result.isolatedParticles.end(), far.begin(), far.end());
        std::sort(result.isolatedParticles.begin(), result.isolatedParticles.end());
        stats.isolated += far.size();
    }

    const auto t = ctx.scope("level set");
    levelset::GridInfo info;
    info.particles = ps.size();
    info.isolated = result.isolatedParticles.size();
    info.source = source;
    if (params.adaptive) {
        AdaptiveGrid& a = result.adaptive;
        a.level2 =
            levelset::finishLevelSet(tree, params, Level{2 * level.voxelSize}, false, info, ctx);
        a.level3 = levelset::finishLevelSet(fine, params, level, false, info, ctx);
        a.level3->setName(AdaptiveGrid::kLevel3Name);
        a.levels = openvdb::Int32Grid::create(levels);
        a.levels->setTransform(Level{4 * level.voxelSize}.transform());
        a.levels->setName(AdaptiveGrid::kLevelsName);
        a.levels->insertMeta("fluidsurf:curvature_threshold",
                             openvdb::DoubleMetadata(params.curvatureThreshold));
        result.grid = a.level2;
    } else {
        result.grid = levelset::finishLevelSet(tree, params, level,
                                               params.method != FieldMethod::NarrowBand, info, ctx);
    }
    stats.activeVoxels = result.grid->activeVoxelCount();
    stats.leaves = result.grid->tree().leafCount();
    return result;
}

} // namespace

RasterizeResult rasterizeParticles(const ParticleSet& ps, const Params& params, Context& ctx,
                                   const std::string& source)
{
    ps.validate();
    // the first non-finite or far-out position, on all threads (one thread takes 14 ms for the
    // 13.1M drop); before the parameters, whose radius may have been estimated from them
    const size_t bad = util::withThreads(ctx, [&] {
        return tbb::parallel_reduce(
            tbb::blocked_range<size_t>(0, ps.size(), 65536), ps.size(),
            [&](const tbb::blocked_range<size_t>& r, size_t first) {
                for (size_t i = r.begin(); i < r.end() && i < first; ++i)
                    if (!ps.positions[i].isWithinRange()) return i;
                return first;
            },
            [](size_t a, size_t b) { return std::min(a, b); });
    });
    if (bad < ps.size() && !ps.positions[bad].isFinite())
        throw ValueError("particle " + std::to_string(bad) + " has a non-finite position");
    if (bad < ps.size()) {
        const Vec3f& p = ps.positions[bad];
        char text[240];
        std::snprintf(text, sizeof(text),
                      "particle %zu lies at (%g, %g, %g), beyond +-%g world units, where float32 "
                      "distances overflow; scale the positions down (e.g. to metres), or drop "
                      "such particles (--drop-nonfinite)",
                      bad, double(p.x), double(p.y), double(p.z), kMaxCoordinate);
        throw ValueError(text);
    }
    params.validate();
    openvdb::initialize();
    if (ctx.device() == Device::Cuda && params.method == FieldMethod::Scatter)
        throw ValueError("the scatter baseline runs on the CPU only (--device cpu)");
    const backend::AutoDevice autoDevice(ctx, ps.size()); // (Auto: the CPU for a small run)
    RasterizeResult result =
        util::withThreads(ctx, [&] { return rasterize(ps, params, ctx, source); });
    if (!autoDevice.why().empty()) result.stats.device += " (" + autoDevice.why() + ")";
    return result;
}

RasterizeResult rasterizeParticles(const ParticleSet& ps, const Params& params,
                                   const std::string& source)
{
    Context ctx;
    return rasterizeParticles(ps, params, ctx, source);
}

} // namespace fluidsurf
