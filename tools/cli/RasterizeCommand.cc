// RasterizeCommand.cc - `fluidsurf rasterize IN -o OUT.vdb`: particle frame(s) to narrow-band
// level sets. Options are the Params fields, lengths relative to the particle radius r.
#include "Commands.h"
#include "Frames.h"
#include "Progress.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/Rasterize.h>
#include <fluidsurf/SpacingEstimate.h>
#include <fluidsurf/io/ParticleIO.h>

#include <tbb/global_control.h>

#include <sys/resource.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <memory>

namespace fluidsurf {
namespace cli {

namespace {
struct RasterizeOptions
{
    std::string input, output, frames, field = "ssp07", method = "narrow-band";
    double radius = 0, voxel = 1, influence = 4, smoothing = 4, band = 2, halfWidth = 3;
    double tLow = 0.4, tHigh = 3.5, colorField = 0.9;
    int surfaceNeighbours = 25, splashNeighbours = 3, threads = 0;
    bool ignoreRadiusAttribute = false, keepIsolated = false, dropNonFinite = false, quiet = false, verbose = false;
};

bool endsWith(const std::string& s, const std::string& suffix)
{
    return s.size() >= suffix.size() && s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

double peakRssMiB()
{
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_maxrss) / 1024.0;
}

/// The radius r: -r, else the radius attribute's largest value, else an estimate. Says which.
double chooseRadius(const RasterizeOptions& o, const ParticleSet& ps, bool print)
{
    if (o.radius > 0) return o.radius;
    if (!o.ignoreRadiusAttribute)
        if (const Attribute* a = ps.find(AttributeRole::Radius)) {
            const float r = a->floats.empty() ? 0.f : *std::max_element(a->floats.begin(), a->floats.end());
            if (r > 0) {
                if (print) std::printf("radius r = %g (largest value of the attribute '%s')\n", r, a->name.c_str());
                return r;
            }
        }
    const SpacingEstimate est = estimateSpacing(ps);
    if (!(est.radius > 0))
        throw ValueError("cannot estimate the particle radius (fewer than two particles, or all isolated); pass -r");
    if (print)
        std::printf("radius r ~ %g (ESTIMATE: half the median nearest-neighbour distance; pass -r with the "
                    "simulator's radius)\n", est.radius);
    return est.radius;
}
} // namespace

Runner addRasterizeCommand(CLI::App& app)
{
    auto o = std::make_shared<RasterizeOptions>();
    CLI::App* cmd = app.add_subcommand("rasterize", "Particle frame(s) to a narrow-band SSP07 level set (.vdb)");
    cmd->add_option("input", o->input, "particle file or frame pattern")->required();
    cmd->add_option("-o,--output", o->output, "output .vdb file or pattern")->required();
    cmd->add_option("--frames", o->frames, "frame range A-B for a pattern");
    cmd->add_option("-r,--radius", o->radius, "particle radius r = half the rest spacing, world units "
                                              "(default: the radius attribute, else an estimate)");
    auto rel = [&](const char* name, double& v, const char* text) {
        cmd->add_option(name, v, text)->capture_default_str()->check(CLI::PositiveNumber);
    };
    rel("--voxel", o->voxel, "voxel (Marching Cubes cell) size, in r");
    rel("--influence", o->influence, "influence radius R of the field kernel, in r");
    rel("--smoothing-length", o->smoothing, "SPH smoothing length h for neighbour counts, in r");
    rel("--band", o->band, "narrow band half width around surface particles, in r (at least 1 + voxel)");
    rel("--half-width", o->halfWidth, "level-set background, in voxels");
    cmd->add_option("--t-low", o->tLow, "SSP07 t_low")->capture_default_str();
    cmd->add_option("--t-high", o->tHigh, "SSP07 t_high")->capture_default_str();
    cmd->add_option("--surface-neighbours", o->surfaceNeighbours, "fewer neighbours within h: surface particle")
        ->capture_default_str();
    cmd->add_option("--splash-neighbours", o->splashNeighbours, "fewer neighbours within h: splash particle")
        ->capture_default_str();
    cmd->add_option("--color-field", o->colorField, "color field below this: surface particle")->capture_default_str();
    cmd->add_option("--field", o->field, "ssp07 or zb05")->capture_default_str()->check(CLI::IsMember({"ssp07", "zb05"}));
    cmd->add_option("--method", o->method, "narrow-band, or the baselines gather-full and scatter")
        ->capture_default_str()->check(CLI::IsMember({"narrow-band", "gather-full", "scatter"}));
    cmd->add_option("-j,--threads", o->threads, "worker threads (default: all cores)")->check(CLI::NonNegativeNumber);
    cmd->add_flag("--ignore-radius-attribute", o->ignoreRadiusAttribute, "use r for every particle even with pscale");
    cmd->add_flag("--keep-isolated", o->keepIsolated, "isolated particles become spheres of radius r in the grid");
    cmd->add_flag("--drop-nonfinite", o->dropNonFinite, "drop particles with NaN/Inf coordinates instead of failing");
    cmd->add_flag("-q,--quiet", o->quiet, "no progress bar and no per-frame lines");
    cmd->add_flag("-v,--verbose", o->verbose, "per-stage timings and peak memory");
    cmd->footer("Examples:\n"
                "  fluidsurf rasterize frame.bgeo -r 0.025 -o frame.vdb\n"
                "  fluidsurf rasterize frame.bgeo -r 0.025 --voxel 0.5 -o fine.vdb      (voxel r/2)\n"
                "  fluidsurf rasterize 'sim/f_{:04}.bgeo' -r 0.025 -o 'vdb/f_{:04}.vdb' --frames 1-100\n"
                "Writes an OpenVDB level set named 'surface' (negative inside, background\n"
                "half-width * voxel). Isolated particles (no neighbour within h) are not in the grid.");
    return [o]() {
        const auto jobs = planFrames(o->input, o->output, o->frames);
        for (const FrameJob& job : jobs)
            if (!endsWith(job.output, ".vdb")) throw ValueError("output '" + job.output + "' must end in .vdb");
        std::unique_ptr<tbb::global_control> threads;
        if (o->threads > 0)
            threads = std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, o->threads);
        io::ReadOptions ro;
        ro.dropNonFinite = o->dropNonFinite;
        Progress bar(jobs.size(), "rasterize", o->quiet);
        double radius = 0;
        const auto start = std::chrono::steady_clock::now();
        for (size_t i = 0; i < jobs.size(); ++i) {
            bar.update(i, jobs[i].input);
            const auto t0 = std::chrono::steady_clock::now();
            io::ReadInfo ri;
            const ParticleSet ps = io::readParticles(jobs[i].input, ro, &ri);
            const double readSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
            // One radius for the whole sequence: surfaces of neighbouring frames must match.
            if (i == 0) radius = chooseRadius(*o, ps, !o->quiet);
            Params p = Params::fromRadius(radius);
            p.voxelSize = o->voxel * radius;
            p.influenceRadius = o->influence * radius;
            p.smoothingLength = o->smoothing * radius;
            p.bandWidth = o->band * radius;
            p.halfWidth = o->halfWidth;
            p.tLow = o->tLow, p.tHigh = o->tHigh;
            p.surfaceNeighbours = o->surfaceNeighbours, p.splashNeighbours = o->splashNeighbours;
            p.colorFieldThreshold = o->colorField;
            p.perParticleRadii = !o->ignoreRadiusAttribute;
            p.keepIsolated = o->keepIsolated;
            p.field = fieldFromName(o->field);
            p.method = methodFromName(o->method);
            const RasterizeResult res = rasterizeParticles(ps, p, jobs[i].input);
            const auto t1 = std::chrono::steady_clock::now();
            writeLevelSet({res.grid}, jobs[i].output);
            const double writeSeconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - t1).count();
            const RasterizeStats& s = res.stats;
            if (!o->quiet && !bar.enabled()) {
                std::printf("%s -> %s: %zu particles (%zu surface, %zu splash, %zu isolated%s), "
                            "%zu active voxels, %.3f s\n",
                            jobs[i].input.c_str(), jobs[i].output.c_str(), s.particles, s.surface, s.splash,
                            s.isolated, o->keepIsolated ? " kept" : " left out", s.activeVoxels, readSeconds + s.totalSeconds() + writeSeconds);
                if (ri.droppedNonFinite) std::printf("  %zu non-finite particles dropped\n", ri.droppedNonFinite);
            }
            if (o->verbose) {
                std::printf("  %-16s %8.4f s\n", "read", readSeconds);
                for (const StageTime& st : s.stages) std::printf("  %-16s %8.4f s\n", st.name.c_str(), st.seconds);
                std::printf("  %-16s %8.4f s\n", "write", writeSeconds);
                double fieldSeconds = 0;
                for (const StageTime& st : s.stages)
                    if (st.name == "field") fieldSeconds = st.seconds;
                std::printf("  field evaluations %zu (%.1f M/s; %zu of them completing the band), band half "
                            "width %g r, voxel %g r\n",
                            s.fieldEvaluations, s.fieldEvaluations / std::max(1e-9, fieldSeconds) * 1e-6,
                            s.bandCompletion, s.bandWidth / radius, o->voxel);
                std::printf("  peak memory %.1f MiB\n", peakRssMiB());
            }
        }
        bar.finish();
        const double secs = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (jobs.size() > 1 && !o->quiet) std::printf("rasterized %zu frames in %.2f s\n", jobs.size(), secs);
        return 0;
    };
}

} // namespace cli
} // namespace fluidsurf
