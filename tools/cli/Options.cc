// Options.cc - shared pipeline options, the report, Ctrl-C.
#include "Options.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/MemoryBudget.h>
#include <fluidsurf/SpacingEstimate.h>
#include <fluidsurf/io/AtomicFile.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <csignal>
#include <cstdio>
#include <optional>
#include <thread>

#include <semaphore.h>
#include <time.h>
#include <unistd.h>

namespace fluidsurf {
namespace cli {

namespace {
std::atomic<bool> gInterrupted{false};
std::atomic<int> gSignal{0};
sem_t gSignals; // posted by the handler (sem_post is async-signal-safe), waited for below

/// How long a stop may take after the signal before the watchdog ends the process: the loops
/// check the flag once per range, well within it, but a reader of one huge block, OpenMesh's
/// decimater or a command without checks (info) would not stop at all.
constexpr double kGraceSeconds = 0.7;

extern "C" void onInterrupt(int signal)
{
    if (!gInterrupted.exchange(true)) gSignal.store(signal);
    ::sem_post(&gSignals); // a second signal: the watchdog stops at once
}

/// Waits for the first signal, then for the run to end on its own within kGraceSeconds (the
/// process ends, and this thread with it) or for a second signal; then removes every temporary
/// still being written, says so, and ends the process with 128 + the signal.
void watchdog()
{
    while (::sem_wait(&gSignals) != 0) {
    }
    struct timespec deadline;
    ::clock_gettime(CLOCK_REALTIME, &deadline);
    deadline.tv_nsec += long(kGraceSeconds * 1e9);
    deadline.tv_sec += deadline.tv_nsec / 1000000000L, deadline.tv_nsec %= 1000000000L;
    while (::sem_timedwait(&gSignals, &deadline) != 0 && errno == EINTR) {
    }
    io::removeLiveTemporaries();
    const char text[] = "fluidsurf: interrupted; no partial output was written\n";
    (void)!::write(2, text, sizeof(text) - 1);
    ::_exit(interruptExitCode());
}
} // namespace

void installInterruptHandler()
{
    ::sem_init(&gSignals, 0, 0);
    std::thread(watchdog).detach();
    std::signal(SIGINT, onInterrupt);
    std::signal(SIGTERM, onInterrupt);
    // (a process started again for huge pages comes with them blocked, any that came pending:
    // ProcessMemory.cc)
    sigset_t stops;
    sigemptyset(&stops), sigaddset(&stops, SIGINT), sigaddset(&stops, SIGTERM);
    pthread_sigmask(SIG_UNBLOCK, &stops, nullptr);
}

int interruptExitCode()
{
    const int signal = gSignal.load();
    return 128 + (signal ? signal : SIGINT);
}

bool interrupted()
{
    return gInterrupted.load();
}

void stopIfInterrupted(const Context& ctx)
{
    if (interrupted()) throw Cancelled("interrupted");
    ctx.throwIfCancelled();
}

namespace {
/// CLI11's PositiveNumber lets "nan" and "inf" through.
const CLI::Validator kPositiveFinite(
    [](std::string& text) {
        double v = 0;
        try {
            size_t used = 0;
            v = std::stod(text, &used);
            if (used != text.size()) return std::string("'" + text + "' is not a number");
        } catch (const std::exception&) {
            return std::string("'" + text + "' is not a number");
        }
        if (!std::isfinite(v) || !(v > 0))
            return std::string("must be a positive finite number (got " + text + ")");
        return std::string();
    },
    "POSITIVE");
} // namespace

void addFieldOptions(CLI::App* cmd, PipelineOptions& o)
{
    Params& f = o.params.field;
    cmd->add_option("-r,--radius", o.params.radius,
                    "particle radius r = half the rest spacing, world units "
                    "(default: the radius attribute, else an estimate)")
        ->check(kPositiveFinite);
    auto rel = [&](const char* name, double& v, const char* text) {
        cmd->add_option(name, v, text)->capture_default_str()->check(kPositiveFinite);
    };
    rel("--voxel", f.voxelSize, "voxel (Marching Cubes cell) size, in r");
    rel("--influence", f.influenceRadius, "influence radius R of the field kernel, in r");
    rel("--smoothing-length", f.smoothingLength,
        "SPH smoothing length h for neighbour counts, in r");
    rel("--band", f.bandWidth,
        "narrow band half width around surface particles, in r (at least 1 + voxel)");
    rel("--half-width", f.halfWidth, "level-set background, in voxels");
    cmd->add_option("--t-low", f.tLow, "SSP07 t_low")->capture_default_str();
    cmd->add_option("--t-high", f.tHigh, "SSP07 t_high")->capture_default_str();
    cmd->add_option("--radius-scale", f.radiusScale,
                    "phi = |x - xbar| - S rbar f: 1 is SSP07 as published (a flat face 0.87 r "
                    "above its particles), 1.096 puts a lattice face at r")
        ->capture_default_str()
        ->check(CLI::Range(0.5, 2.0));
    cmd->add_option("--surface-neighbours", f.surfaceNeighbours,
                    "fewer neighbours within h: surface particle")
        ->capture_default_str();
    cmd->add_option("--splash-neighbours", f.splashNeighbours,
                    "fewer neighbours within h: splash particle")
        ->capture_default_str();
    cmd->add_option("--color-field", f.colorFieldThreshold,
                    "color field below this: surface particle")
        ->capture_default_str();
    cmd->add_option("--field", o.field,
                    "ssp07, zb05, ssp07-aniso (SSP07 with anisotropic kernels, [YT10]'s PCA: "
                    "flatter faces), or yt10 ([YT10]'s density field with those kernels, "
                    "thesis 4.4: phi = (iso level - density) R)")
        ->capture_default_str()
        ->check(CLI::IsMember({"ssp07", "zb05", "ssp07-aniso", "yt10"}));
    cmd->add_option("--iso-level", f.isoLevel,
                    "yt10: the density the surface passes through (about 1 inside the fluid; "
                    "0.5 puts a flat lattice face r above its particles' centres)")
        ->capture_default_str()
        ->check(CLI::Range(0.001, 0.999));
    cmd->add_option(
           "--aniso-ratio", f.anisotropyRatio,
           "ssp07-aniso, yt10: a kernel's longest axis over its shortest (R), at most (k_r)")
        ->capture_default_str()
        ->check(CLI::Range(1.0, 8.0));
    rel("--aniso-radius", f.anisotropyRadius,
        "ssp07-aniso, yt10: radius of each particle's PCA, in r");
    cmd->add_option(
           "--aniso-neighbours", f.anisotropyNeighbours,
           "ssp07-aniso, yt10: fewer neighbours within the PCA radius keep the sphere (N_eps)")
        ->capture_default_str()
        ->check(CLI::Range(0, 10000));
    cmd->add_option("--centre-smoothing", f.centreSmoothing,
                    "ssp07-aniso, yt10: how far a surface particle's kernel centre moves to its "
                    "neighbours' mean, 0 to 1 (lambda)")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 1.0));
    cmd->add_option("--method", o.method, "narrow-band, or the baselines gather-full and scatter")
        ->capture_default_str()
        ->check(CLI::IsMember({"narrow-band", "gather-full", "scatter"}));
    cmd->add_option("--device", o.device,
                    "cpu, cuda (the narrow band on the GPU: sort, classify, band and gather, "
                    "then marching cubes; gather-full gathers there) or auto (cuda when a usable "
                    "GPU is present and the run has enough particles for it to pay, frames "
                    "times particles: 1M at 4 threads, 7.5M at 16; README, 'Which device')")
        ->capture_default_str()
        ->check(CLI::IsMember({"cpu", "cuda", "auto"}));
    cmd->add_flag("--ignore-radius-attribute", o.ignoreRadiusAttribute,
                  "use r for every particle even with pscale");
    cmd->add_flag("--keep-isolated", f.keepIsolated,
                  "isolated particles become spheres of radius r in the grid");
    cmd->add_flag("--adaptive", f.adaptive,
                  "curvature-adaptive 3-level grid (thesis ch. 6): flat parts at 2 voxels, "
                  "curved parts and splashes at --voxel; .vdb output holds the grids surface "
                  "(2 voxels), surface_fine (1 voxel) and levels (4 voxels)");
    cmd->add_option("--curvature-threshold", f.curvatureThreshold,
                    "with --adaptive: mean particle curvature (thesis eq. 6.1-6.3) from which a "
                    "coarse cell gets the finest level; lower keeps more detail")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber);
    cmd->add_option("--level-tolerance", f.levelTolerance,
                    "with --adaptive: a flat cell is refined too where its surface would move by "
                    "more than this many voxels at the finer level (0: curvature alone, as in "
                    "the thesis; larger: fewer triangles, farther from the uniform mesh); a flat "
                    "cell with more finest-level neighbours than flat ones is refined either way")
        ->capture_default_str()
        ->check(CLI::NonNegativeNumber);
}

void addRunOptions(CLI::App* cmd, PipelineOptions& o, Makes makes)
{
    if (makes == Makes::MeshedLevelSet)
        cmd->add_option("--mesher", o.mesher,
                        "mc (our marching cubes) or openvdb (OpenVDB's volumeToMesh)")
            ->capture_default_str()
            ->check(CLI::IsMember({"mc", "openvdb"}));
    if (makes != Makes::LevelSet)
        cmd->add_flag("--check", o.check,
                      "check the mesh (boundary and non-manifold edges, orientation, ...) and "
                      "print it");
    cmd->add_option("-j,--threads", o.threads, "worker threads (default: all cores)")
        ->check(CLI::Range(0, Context::kMaxThreads));
    cmd->add_option("--max-memory", o.maxMemory,
                    "the most memory a frame may need, e.g. 8G or 500M: a request estimated "
                    "past it (a voxel too small for the frame, a level set of huge tiles) fails "
                    "at once with the estimate (default: 80% of this machine's memory)");
    cmd->add_flag("-q,--quiet", o.quiet, "no progress bar and no per-frame lines");
    cmd->add_flag("-v,--verbose", o.verbose,
                  "the timing tree of each frame (share of the total, peak memory)");
    cmd->add_option("--stats", o.stats,
                    "write every frame's timing tree and counts to this JSON file");
}

ReconstructParams PipelineOptions::resolved() const
{
    ReconstructParams p = params;
    p.field.field = fieldFromName(field);
    p.field.method = methodFromName(method);
    p.field.perParticleRadii = !ignoreRadiusAttribute;
    p.mesh.mesher = mesherFromName(mesher);
    p.post.isolated = isolatedModeFromName(isolated);
    p.post.decimator = decimatorFromName(decimator);
    p.post.volume = volumeTargetFromName(volume);
    if (decimate == "off") {
        p.post.decimate = 0;
    } else {
        size_t used = 0;
        try {
            p.post.decimate = std::stod(decimate, &used);
        } catch (const std::exception&) {
            used = 0;
        }
        if (used != decimate.size())
            throw ValueError("--decimate " + decimate +
                             ": a fraction of the triangles to remove (0.8) or 'off'");
    }
    if (raw) p.post.decimate = 0, p.post.decimateError = 0, p.post.smooth = 0, p.post.subdivide = 0;
    return p;
}

size_t parseMemorySize(const std::string& text)
{
    size_t used = 0;
    double value = -1;
    try {
        value = std::stod(text, &used);
    } catch (const std::exception&) {
        used = 0;
    }
    const std::string unit = used ? text.substr(used) : std::string();
    double scale = -1;
    if (unit.empty() || unit == "B") scale = 1;
    if (unit == "K" || unit == "KB" || unit == "KiB") scale = 1024.0;
    if (unit == "M" || unit == "MB" || unit == "MiB") scale = 1024.0 * 1024;
    if (unit == "G" || unit == "GB" || unit == "GiB") scale = 1024.0 * 1024 * 1024;
    if (unit == "T" || unit == "TB" || unit == "TiB") scale = 1024.0 * 1024 * 1024 * 1024;
    const double bytes = value * scale;
    if (!used || scale < 0 || !std::isfinite(bytes) || bytes < 1024.0 * 1024 || bytes > 1e18)
        throw ValueError("--max-memory " + text +
                         ": a size such as 8G, 500M or 1048576 (bytes), at least 1M");
    return size_t(bytes);
}

void PipelineOptions::configure(Context& ctx) const
{
    ctx.setDevice(deviceFromName(device));
    ctx.setThreads(threads);
    if (!maxMemory.empty()) { // the readers' too: they have no context
        ctx.setMemoryBudget(parseMemorySize(maxMemory));
        setProcessMemoryBudget(parseMemorySize(maxMemory));
    }
    ctx.setProgress([](const ProgressEvent&) { return !interrupted(); });
}

std::unique_ptr<tbb::global_control> PipelineOptions::setUp(Context& ctx) const
{
    // --stats is written last, after every frame: its folder is checked before the first
    if (!stats.empty()) io::requireWritableFolder(stats);
    configure(ctx);
    if (threads <= 0) return nullptr;
    return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                 size_t(threads));
}

void addAttributesOption(CLI::App* cmd, PipelineOptions& o, const char* where)
{
    cmd->add_option(
           "--attributes", o.params.attributes,
           std::string("particle attributes to carry along, e.g. v,density,id (floats by a "
                       "linear fit over the particles within R: a linear field such as a "
                       "rotation comes out exact; integers from the nearest particle); ") +
               where)
        ->delimiter(',');
}

double chooseSequenceRadius(const PipelineOptions& o, const ParticleSet& first, Context& ctx)
{
    const RadiusChoice c = chooseRadius(first, o.params.radius, !o.ignoreRadiusAttribute, ctx);
    if (!o.quiet && c.source == RadiusSource::Attribute)
        std::printf("radius r = %g (%s)\n", c.radius, c.detail.c_str());
    if (!o.quiet && c.source == RadiusSource::Estimated)
        std::printf("radius r ~ %g (ESTIMATE: %s; pass -r with the simulator's radius)\n", c.radius,
                    c.detail.c_str());
    return c.radius;
}

void warnIfEmpty(const std::string& input, const ParticleSet& ps, const RasterizeStats& s,
                 double radius, bool noTriangles)
{
    if (ps.empty() || (s.activeVoxels > 0 && !noTriangles)) return;
    std::string why;
    if (s.isolated == s.particles) {
        why = "every particle is isolated (no neighbour within h); --keep-isolated makes them "
              "spheres";
    } else {
        const SpacingEstimate est = estimateSpacing(ps);
        char text[200];
        if (ps.size() > 1 && (est.sampled == 0 || est.medianNearest == 0))
            std::snprintf(text, sizeof(text),
                          "most particles coincide (the median distance to the nearest one is 0)");
        else if (est.radius > 0 && radius / est.radius > 0.5 && radius / est.radius < 2)
            std::snprintf(text, sizeof(text),
                          "r = %g matches the spacing; check the lengths relative to it (--voxel, "
                          "--influence, --band, --smoothing-length)",
                          radius);
        else if (est.radius > 0)
            std::snprintf(text, sizeof(text),
                          "r = %g is %.3g times the radius the spacing suggests (%g); check -r and "
                          "the lengths relative to it",
                          radius, radius / est.radius, est.radius);
        else
            std::snprintf(text, sizeof(text), "check -r (%g) and the lengths relative to it",
                          radius);
        why = text;
    }
    std::fprintf(stderr, "fluidsurf: warning: %s: no surface from %zu particles: %s\n",
                 input.c_str(), ps.size(), why.c_str());
}

ParticleSet readFrame(const PipelineOptions& o, Context& ctx, const std::string& path,
                      const io::ReadOptions& read, io::ReadInfo& info, bool first,
                      ReconstructParams& params)
{
    ctx.timing().clear();
    ParticleSet ps;
    {
        const auto t = ctx.scope("read");
        ps = io::readParticles(path, read, &info);
    }
    stopIfInterrupted(ctx);
    if (first) params.radius = chooseSequenceRadius(o, ps, ctx);
    return ps;
}

std::vector<std::pair<std::string, double>> fieldCounts(const RasterizeStats& s)
{
    std::vector<std::pair<std::string, double>> counts = {
        {"particles", double(s.particles)},
        {"interior", double(s.interior)},
        {"surface", double(s.surface)},
        {"splash", double(s.splash)},
        {"isolated", double(s.isolated)},
        {"active_voxels", double(s.activeVoxels)},
        {"leaves", double(s.leaves)},
        {"field_evaluations", double(s.fieldEvaluations)},
        {"band_completion", double(s.bandCompletion)},
        {"band_half_width", s.bandWidth}};
    if (s.level2Cells + s.level3Cells)
        counts.insert(counts.end(), {{"level2_cells", double(s.level2Cells)},
                                     {"level3_cells", double(s.level3Cells)},
                                     {"level3_completion_cells", double(s.completionCells)},
                                     {"level3_refined_cells", double(s.refinedCells)},
                                     {"level3_island_cells", double(s.islandCells)},
                                     {"level2_crossing_probes", double(s.level2CrossingProbes)},
                                     {"subsampled_values", double(s.subsampled)}});
    return counts;
}

std::vector<std::pair<std::string, double>> meshCounts(const MeshReport& r)
{
    return {{"vertices", double(r.vertices)},
            {"triangles", double(r.triangles)},
            {"boundary_edges", double(r.boundaryEdges)},
            {"non_manifold_edges", double(r.nonManifoldEdges)},
            {"components", double(r.components)},
            {"thin_triangles", double(r.thinTriangles)},
            {"min_angle_deg", r.minAngleDegrees},
            {"volume", r.volume},
            {"area", r.area}};
}

namespace {

/// -v: the adaptive grid's cells and triangles per level and its crack patches, when the counts
/// hold them (an adaptive reconstruction or the mesh of an adaptive .vdb).
void printAdaptiveCounts(const std::vector<std::pair<std::string, double>>& counts)
{
    auto count = [&](const char* name) -> std::optional<double> {
        for (const auto& [key, value] : counts)
            if (key == name) return value;
        return std::nullopt;
    };
    const auto t2 = count("level2_triangles"), t3 = count("level3_triangles"),
               patches = count("patch_triangles");
    if (!t2 || !t3 || !patches) return;
    const auto c2 = count("level2_cells"), c3 = count("level3_cells");
    const double all = *t2 + *t3 + *patches;
    std::printf("  adaptive grid: level 2 %.0f cells, %.0f triangles; level 3 %.0f cells",
                c2 ? *c2 : 0, *t2, c3 ? *c3 : 0);
    if (const auto refined = count("level3_refined_cells"))
        std::printf(
            " (%.0f refined by the level tolerance, %.0f level-2 islands closed, %.0f added "
            "to complete the surface)",
            *refined, count("level3_island_cells").value_or(0),
            count("level3_completion_cells").value_or(0));
    std::printf(", %.0f triangles; crack patches %.0f triangles (%.2f%%), %.0f crack points "
                "merged",
                *t3, *patches, all > 0 ? 100 * *patches / all : 0.0,
                count("merged_crack_points").value_or(0));
    if (const auto open = count("open_cracks"); open && *open > 0)
        std::printf("; %.0f cracks left open", *open);
    std::printf("\n");
}

} // namespace

void Report::frame(const std::string& input, const Context& ctx,
                   const std::vector<std::pair<std::string, double>>& counts,
                   const RasterizeStats* field)
{
    if (mOptions.verbose) {
        std::printf("%s", ctx.timing().format().c_str());
        if (field) {
            std::printf("  field on %s", field->device.c_str());
            if (!field->gpuStages.empty()) {
                std::printf(" (CUDA events:");
                for (const StageTime& st : field->gpuStages)
                    std::printf(" %s %.2f ms", st.name.c_str(), st.seconds * 1e3);
                std::printf("; %.1f MiB of device memory)", double(field->gpuBytes) / (1 << 20));
            }
            std::printf("\n  field evaluations %zu (%zu of them completing the band)\n",
                        field->fieldEvaluations, field->bandCompletion);
        }
        printAdaptiveCounts(counts);
        std::printf("  peak memory %.1f MiB\n", peakMemoryMiB());
    }
    if (mOptions.stats.empty()) return;
    auto quoted = [](const std::string& text) {
        std::string q = "\"";
        for (const char c : text)
            if (c == '"' || c == '\\')
                q += '\\', q += c;
            else if (static_cast<unsigned char>(c) >= 0x20)
                q += c;
        return q + "\"";
    };
    std::string json = "{\"input\": " + quoted(input) + ", \"counts\": {";
    char num[64];
    for (size_t i = 0; i < counts.size(); ++i) {
        std::snprintf(num, sizeof(num), "%.17g", counts[i].second);
        json += (i ? ", \"" : "\"") + counts[i].first + "\": " + num;
    }
    json += "}, \"device\": " + quoted(field ? field->device : "cpu");
    json += ", \"timing\": " + ctx.timing().toJson() + "}";
    mFrames.push_back(json);
}

void Report::finish() const
{
    if (mOptions.stats.empty()) return;
    std::string json = "{\"frames\": [\n";
    for (size_t i = 0; i < mFrames.size(); ++i)
        json += (i ? ",\n" : "") + mFrames[i];
    char peak[64];
    std::snprintf(peak, sizeof(peak), "%.1f", peakMemoryMiB());
    json += std::string("\n], \"peak_memory_mib\": ") + peak + "}\n";
    io::writeFileAtomic(mOptions.stats, json.data(), json.size());
}

} // namespace cli
} // namespace fluidsurf
