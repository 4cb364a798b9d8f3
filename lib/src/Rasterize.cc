// Rasterize.cc - the rasterize pipeline: runs the stages in order and times each one.
#include <fluidsurf/Error.h>
#include <fluidsurf/Rasterize.h>

#include "classify/Classify.h"
#include "field/CudaField.h"
#include "field/GatherField.h"
#include "field/ScatterField.h"
#include "levelset/LevelSet.h"
#include "narrowband/CompleteBand.h"
#include "narrowband/NarrowBand.h"
#include "neighbors/CellIndex.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <future>

namespace fluidsurf {

double RasterizeStats::totalSeconds() const
{
    double t = 0;
    for (const StageTime& s : stages)
        t += s.seconds;
    return t;
}

namespace {
class StageClock
{
public:
    explicit StageClock(std::vector<StageTime>& out) : mOut(out) {}
    void done(const char* name)
    {
        const auto now = std::chrono::steady_clock::now();
        mOut.push_back({name, std::chrono::duration<double>(now - mLast).count()});
        mLast = now;
    }

private:
    std::vector<StageTime>& mOut;
    std::chrono::steady_clock::time_point mLast = std::chrono::steady_clock::now();
};

/// Per-particle radii from the radius attribute, or empty for the uniform radius.
std::vector<float> particleRadii(const ParticleSet& ps, const Params& params)
{
    const Attribute* a = params.perParticleRadii ? ps.find(AttributeRole::Radius) : nullptr;
    if (!a) return {};
    for (size_t i = 0; i < a->floats.size(); ++i)
        if (!(a->floats[i] > 0) || !std::isfinite(a->floats[i]))
            throw ValueError("radius attribute '" + a->name + "' of particle " + std::to_string(i) +
                             " is " + std::to_string(a->floats[i]) +
                             "; radii must be positive (or ignore the attribute)");
    return a->floats;
}

/// neighbors -> classify -> band (or bounding volume) -> field -> completion on the CPU, with
/// the field gather on the GPU when onGpu.
openvdb::FloatTree::Ptr cpuStages(const ParticleSet& ps, const std::vector<float>& radii,
                                  const Params& params, bool onGpu, RasterizeResult& result,
                                  StageClock& clock)
{
    RasterizeStats& stats = result.stats;
    const double cellSize = std::min(params.influenceRadius, params.smoothingLength);
    neighbors::CellIndex index = neighbors::buildCellIndex(
        ps.positions.data(), radii.empty() ? nullptr : radii.data(), ps.size(), cellSize);
    clock.done("neighbors");

    const classify::Classification classes = classify::classifyParticles(index, params);
    stats.interior = classes.interior, stats.surface = classes.surface;
    stats.splash = classes.splash, stats.isolated = classes.isolated;
    if (!params.keepIsolated)
        for (size_t i = 0; i < classes.classes.size(); ++i)
            if (classes.classes[i] == classify::Isolated)
                result.isolatedParticles.push_back(index.order[i]);
    std::sort(result.isolatedParticles.begin(), result.isolatedParticles.end());
    clock.done("classify");

    const float background = float(params.background());
    openvdb::FloatTree::Ptr tree;
    if (params.method == FieldMethod::NarrowBand) {
        const openvdb::MaskTree::Ptr band =
            narrowband::buildNarrowBand(index, classes, params, stats.bandWidth);
        tree = std::make_shared<openvdb::FloatTree>(*band, background, openvdb::TopologyCopy());
        clock.done("narrow band");
    }
    // Isolated particles take no part in the field.
    if (classes.isolated && !params.keepIsolated) {
        std::vector<uint8_t> keep(classes.classes.size());
        for (size_t i = 0; i < keep.size(); ++i)
            keep[i] = classes.classes[i] != classify::Isolated;
        index = neighbors::selectParticles(index, keep);
    }
    if (params.method == FieldMethod::GatherFull) {
        tree = std::make_shared<openvdb::FloatTree>(background);
        const openvdb::CoordBBox box = narrowband::boundingVolume(index, params);
        if (!box.empty()) {
            narrowband::checkDenseMemory(box, sizeof(float) * 1.2, "gather-full");
            tree->denseFill(box, background, true);
        }
        clock.done("bounding volume");
    }
    if (params.method == FieldMethod::Scatter) {
        tree = field::scatterField(index, params, &stats.fieldEvaluations);
    } else if (onGpu) {
        stats.fieldEvaluations = field::evaluateFieldCuda(*tree, index, params, stats);
    } else {
        stats.fieldEvaluations = field::evaluateField(*tree, index, params);
    }
    clock.done("field");
    if (params.method == FieldMethod::NarrowBand) {
        stats.bandCompletion = narrowband::completeBand(*tree, index, params);
        stats.fieldEvaluations += stats.bandCompletion;
        clock.done("complete band");
    }
    return tree;
}
} // namespace

void prepareDevice(Device device)
{
    if (device == Device::Cpu) return;
    // Held until exit: the future's destructor waits for the context, never a half-made one.
    static std::future<void> opening = std::async(std::launch::async, [] { field::cudaUsable(); });
}

RasterizeResult rasterizeParticles(const ParticleSet& ps, const Params& params,
                                   const std::string& source)
{
    params.validate();
    ps.validate();
    openvdb::initialize();
    for (size_t i = 0; i < ps.size(); ++i)
        if (!ps.positions[i].isFinite())
            throw ValueError("particle " + std::to_string(i) + " has a non-finite position");
    if (params.device == Device::Cuda && params.method == FieldMethod::Scatter)
        throw ValueError("the scatter baseline runs on the CPU only (--device cpu)");
    // Looking for the GPU (and creating its context, unless the caller did earlier) runs on a
    // thread while the radii are checked.
    struct GpuCheck
    {
        bool usable = false;
        std::string reason;
    };
    std::future<GpuCheck> gpuCheck;
    if (params.device != Device::Cpu && params.method != FieldMethod::Scatter)
        gpuCheck = std::async(std::launch::async, [] {
            GpuCheck c;
            c.usable = field::cudaUsable(&c.reason);
            return c;
        });
    RasterizeResult result;
    RasterizeStats& stats = result.stats;
    stats.particles = ps.size();
    StageClock clock(stats.stages);

    const std::vector<float> radii = particleRadii(ps, params);
    float maxRadius = float(params.radius);
    for (float r : radii)
        maxRadius = std::max(maxRadius, r);
    stats.bandWidth = narrowband::effectiveBandWidth(params, maxRadius);

    bool onGpu = false;
    if (gpuCheck.valid()) {
        const GpuCheck gpu = gpuCheck.get();
        if (params.device == Device::Cuda && !gpu.usable)
            throw Error("CUDA was requested but there is no usable GPU: " + gpu.reason);
        onGpu = gpu.usable;
        if (onGpu)
            clock.done("cuda context"); // waiting for it, unless prepareDevice made it earlier
    }
    // The narrow band runs on the device from the sort on; gather-full only gathers there.
    openvdb::FloatTree::Ptr tree;
    if (onGpu && params.method == FieldMethod::NarrowBand && ps.size() > 0) {
        try {
            tree = field::rasterizeNarrowBandCuda(ps.positions, radii, params, stats.bandWidth,
                                                  stats, result.isolatedParticles,
                                                  [&](const char* name) { clock.done(name); });
        } catch (const ValueError&) {
            throw; // the input's fault: the CPU would say the same
        } catch (const Error& e) {
            // CUDA failed (out of device memory, ...): auto means "the GPU if it can", so the CPU
            // takes over and says why; an explicit cuda request reports the failure.
            // The CPU stages set every count again; the GPU's stages and memory are only filled
            // on success.
            if (params.device == Device::Cuda) throw;
            stats.device = std::string("cpu (CUDA failed: ") + e.what() + ")";
            result.isolatedParticles.clear();
            onGpu = false;
        }
    }
    if (!tree) tree = cpuStages(ps, radii, params, onGpu, result, clock);

    levelset::GridInfo info;
    info.particles = ps.size();
    info.isolated = result.isolatedParticles.size();
    info.source = source;
    result.grid =
        levelset::finishLevelSet(tree, params, params.method != FieldMethod::NarrowBand, info);
    stats.activeVoxels = result.grid->activeVoxelCount();
    stats.leaves = result.grid->tree().leafCount();
    clock.done("level set");
    return result;
}

} // namespace fluidsurf
