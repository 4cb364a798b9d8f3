// RasterizeCommand.cc - `fluidsurf rasterize IN -o OUT.vdb`: particle frame(s) to narrow-band
// level sets. Parse -> params -> rasterizeParticles -> write -> report.
#include "Commands.h"
#include "Frames.h"
#include "Options.h"
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
                  "drop particles with NaN/Inf coordinates instead of failing");
    addSequenceOptions(cmd, o->sequence);
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
        refuseOverwritingInputs(inputsOf(jobs), outputsOf(jobs));
        ReconstructParams params = po.resolved();
        Context ctx;
        const auto threadLimit = po.setUp(ctx);
        io::ReadOptions ro;
        ro.dropNonFinite = o->dropNonFinite;
        prepareDevice(ctx.device());
        const std::vector<size_t> picked = shardOf(jobs, o->sequence.shard);
        SequenceRun run(o->sequence, po.quiet);
        Progress bar(picked.size(), "rasterize", po.quiet);
        Report report(po);
        bool radiusChosen = false;
        for (size_t k = 0; k < picked.size(); ++k) {
            const size_t i = picked[k];
            if (run.skip({jobs[i].output})) continue;
            if (!radiusChosen && i != 0) {
                chooseSequenceRadiusFrom(po, ctx, jobs[0], ro, params);
                radiusChosen = true;
            }
            run.frame(jobs[i].input, [&] {
                bar.update(k, jobs[i].input);
                io::ReadInfo ri;
                const ParticleSet ps =
                    readFrame(po, ctx, jobs[i].input, ro, ri, !radiusChosen, params);
                radiusChosen = true;
                checkAttributeNames(ps, params.attributes); // before the work
                const RasterizeResult res =
                    rasterizeParticles(ps, params.fieldParams(params.radius), ctx, jobs[i].input);
                openvdb::GridPtrVec grids =
                    res.adaptive.empty() ? openvdb::GridPtrVec{res.grid} : res.adaptive.grids();
                const openvdb::GridPtrVec more =
                    attributeGrids(ps, params.attributes, *res.grid,
                                   params.fieldParams(params.radius).influenceRadius, ctx);
                grids.insert(grids.end(), more.begin(), more.end());
                {
                    const auto t = ctx.scope("write");
                    io::writeLevelSet(grids, jobs[i].output);
                }
                ctx.timing().finish();
                const RasterizeStats& s = res.stats;
                if (!po.quiet && !bar.enabled()) {
                    std::printf(
                        "%s -> %s: %zu particles (%zu surface, %zu splash, %zu isolated%s), "
                        "%zu active voxels, %.3f s\n",
                        jobs[i].input.c_str(), jobs[i].output.c_str(), s.particles, s.surface,
                        s.splash, s.isolated, params.field.keepIsolated ? " kept" : " left out",
                        s.activeVoxels, ctx.timing().root().seconds);
                    if (ri.droppedNonFinite)
                        std::printf("  %zu non-finite particles dropped\n", ri.droppedNonFinite);
                }
                warnIfEmpty(jobs[i].input, ps, s, params.radius, false);
                report.frame(jobs[i].input, ctx, fieldCounts(s), &s);
                stopIfInterrupted(ctx); // Ctrl-C during the write: that frame is complete
            });
        }
        bar.finish();
        report.finish();
        return run.finish("rasterize", picked.size());
    };
}

} // namespace cli
} // namespace fluidsurf
