// RasterizeCommand.cc - `fluidsurf rasterize IN -o OUT.vdb`: particle frame(s) to narrow-band
// level sets. Parse -> params -> rasterizeParticles -> write -> report.
#include "Commands.h"
#include "Frames.h"
#include "Options.h"
#include "ParticleFrames.h"
#include "ProcessMemory.h"
#include "Progress.h"
#include "Sequence.h"

#include <fluidsurf/Rasterize.h>
#include <fluidsurf/TransferAttributes.h>
#include <fluidsurf/io/LevelSetIO.h>
#include <fluidsurf/io/ParticleIO.h>

#include <cstdio>
#include <memory>

namespace fluidsurf {
namespace cli {

namespace {
struct RasterizeOptions
{
    std::string input, output, frames;
    PipelineOptions pipeline;
    SequenceOptions sequence;
    bool dropNonFinite = false;
    size_t inFlight = 0; ///< --in-flight (0: by the threads)
};
} // namespace

Runner addRasterizeCommand(CLI::App& app)
{
    auto o = std::make_shared<RasterizeOptions>();
    CLI::App* cmd = app.add_subcommand("rasterize",
                                       "Particle frame(s) to a narrow-band SSP07 level set (.vdb)");
    cmd->add_option("input", o->input, "particle file or frame pattern")->required();
    cmd->add_option("-o,--output", o->output, "output .vdb file or pattern")->required();
    cmd->add_option("--frames", o->frames, "frame range A-B for a pattern");
    addFieldOptions(cmd, o->pipeline);
    addRunOptions(cmd, o->pipeline, Makes::LevelSet);
    addAttributesOption(cmd, o->pipeline,
                        "written as grids over the level set's band beside it (v as a Vec3fGrid)");
    cmd->add_flag("--drop-nonfinite", o->dropNonFinite,
                  "drop particles with NaN/Inf coordinates (or past 1e15) instead of failing");
    addSequenceOptions(cmd, o->sequence);
    addInFlightOption(cmd, o->inFlight);
    cmd->footer(
        "Examples:\n"
        "  fluidsurf rasterize frame.bgeo -r 0.025 -o frame.vdb\n"
        "  fluidsurf rasterize frame.bgeo -r 0.025 --voxel 0.5 -o fine.vdb      (voxel r/2)\n"
        "  fluidsurf rasterize 'sim/f_{:04}.bgeo' -r 0.025 -o 'vdb/f_{:04}.vdb' --frames 1-100\n"
        "  fluidsurf rasterize 'sim/f_{:04}.bgeo' -r 0.025 -o 'vdb/f_{:04}.vdb' --shard slurm\n"
        "      --skip-existing --keep-going     (in sbatch --array=1-100)\n"
        "  fluidsurf rasterize frame.bgeo -r 0.025 -o frame.vdb -v --stats frame.json\n"
        "Writes an OpenVDB level set named 'surface' (negative inside, background\n"
        "half-width * voxel). Isolated particles (no neighbour within h) are not in the grid.\n"
        "Ctrl-C stops cleanly (exit code 130): no partial file is left.");
    return [o]() {
        const PipelineOptions& po = o->pipeline;
        const auto jobs = planVdbFrames(o->input, o->output, o->frames, "output");
        checkRunFiles(inputsOf(jobs), outputsOf(jobs), po.stats);
        useHugePagesFor(inputBytes(jobs, shardOf(jobs, o->sequence.shard)), po.threads,
                        interrupted);
        ReconstructParams params = po.resolved();
        Context ctx;
        const auto threadLimit = po.setUp(ctx);
        io::ReadOptions ro;
        ro.dropNonFinite = o->dropNonFinite;
        const std::vector<size_t> picked = shardOf(jobs, o->sequence.shard);
        SequenceRun run(o->sequence, po.quiet);
        const std::vector<size_t> todo = run.unfinished(
            picked, [&](size_t i) { return std::vector<std::string>{jobs[i].output}; });
        if (worthPreparingDevice(ctx, jobs, todo)) prepareDevice(ctx.device());
        Progress bar(picked.size(), "rasterize", po.quiet);
        Report report(po);
        struct Made
        {
            RasterizeResult field;
            openvdb::GridPtrVec grids; ///< the level set(s) and the attribute grids
        };
        FrameRun pr{po, jobs, todo, o->inFlight, run, bar};
        using Frame = ParticleFrame<Made>;
        runParticleFrames<Made>(
            pr, ro, params,
            [&](Frame& f) {
                checkAttributeNames(f.particles, f.params.attributes); // before the work
                const Params fp = f.params.fieldParams(f.params.radius);
                Made& m = f.result;
                m.field = rasterizeParticles(f.particles, fp, f.ctx, jobs[f.job].input);
                m.grids = m.field.adaptive.empty() ? openvdb::GridPtrVec{m.field.grid}
                                                   : m.field.adaptive.grids();
                const openvdb::GridPtrVec more = attributeGrids(
                    f.particles, f.params.attributes, *m.field.grid, fp.influenceRadius, f.ctx);
                m.grids.insert(m.grids.end(), more.begin(), more.end());
                // write needs them only for the warning of a frame without surface
                if (m.field.stats.activeVoxels > 0) f.particles = ParticleSet();
            },
            [&](Frame& f) {
                const FrameJob& job = jobs[f.job];
                {
                    const auto t = f.ctx.scope("write");
                    io::writeLevelSet(f.result.grids, job.output);
                }
                f.ctx.timing().finish();
                const RasterizeStats& s = f.result.field.stats;
                if (!po.quiet && !bar.enabled()) {
                    std::printf(
                        "%s -> %s: %zu particles (%zu surface, %zu splash, %zu isolated%s), "
                        "%zu active voxels, %.3f s\n",
                        job.input.c_str(), job.output.c_str(), s.particles, s.surface, s.splash,
                        s.isolated, f.params.field.keepIsolated ? " kept" : " left out",
                        s.activeVoxels, frameSeconds(f.ctx));
                    if (f.readInfo.droppedNonFinite)
                        std::printf("  %zu non-finite particles dropped\n",
                                    f.readInfo.droppedNonFinite);
                }
                warnIfEmpty(job.input, f.particles, s, f.params.radius, false);
                report.frame(job.input, f.ctx, fieldCounts(s), &s);
                stopIfInterrupted(f.ctx); // Ctrl-C during the write: that frame is complete
            });
        bar.finish();
        report.finish();
        return run.finish("rasterize", picked.size());
    };
}

} // namespace cli
} // namespace fluidsurf
