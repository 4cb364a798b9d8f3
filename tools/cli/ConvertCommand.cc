// ConvertCommand.cc - `fluidsurf convert IN OUT`: particle format conversion, sequences too.
#include "Commands.h"
#include "Frames.h"
#include "Options.h"
#include "Progress.h"
#include "Sequence.h"

#include <fluidsurf/MemoryBudget.h>
#include <fluidsurf/io/ParticleIO.h>

#include <cstdio>
#include <memory>

namespace fluidsurf {
namespace cli {

namespace {
struct ConvertOptions
{
    std::string input, output, frames, maxMemory;
    bool dropNonFinite = false, noCompress = false, quiet = false;
    SequenceOptions sequence;
};
} // namespace

Runner addConvertCommand(CLI::App& app)
{
    auto o = std::make_shared<ConvertOptions>();
    CLI::App* cmd = app.add_subcommand(
        "convert", "Convert particle files between formats (reads .vtk .vtu .vtp .bgeo "
                   ".ply .xyz .csv .txt .npy .vdb; writes .vdb .bgeo .bgeo.gz .ply .xyz .vtk)");
    cmd->add_option("input", o->input, "input file or frame pattern")->required();
    cmd->add_option("output", o->output, "output file or frame pattern (format from the extension)")
        ->required();
    cmd->add_option("--frames", o->frames, "frame range A-B for a pattern");
    cmd->add_flag("--drop-nonfinite", o->dropNonFinite,
                  "drop particles with NaN/Inf coordinates (or past 1e15) instead of failing");
    cmd->add_flag("--no-compress", o->noCompress, "write VDB points without Blosc compression");
    cmd->add_flag("-q,--quiet", o->quiet, "no progress bar and no per-frame lines");
    cmd->add_option("--max-memory", o->maxMemory,
                    "the most memory reading a frame may take, e.g. 8G (default: 80% of this "
                    "machine's memory): a file whose header or tree promises more is refused "
                    "with the estimate");
    addSequenceOptions(cmd, o->sequence);
    cmd->footer(
        "Examples:\n  fluidsurf convert frame.vtk frame.vdb\n"
        "  fluidsurf convert 'sim/f_####.bgeo' 'out/f_####.ply' --frames 1-100\n"
        "  fluidsurf convert 'sim/f_####.vtk' 'vdb/f_####.vdb' --shard slurm --skip-existing");
    return [o]() {
        if (!o->maxMemory.empty()) setProcessMemoryBudget(parseMemorySize(o->maxMemory));
        const auto jobs = planFrames(o->input, o->output, o->frames);
        checkRunFiles(inputsOf(jobs), outputsOf(jobs));
        io::ReadOptions ro;
        ro.dropNonFinite = o->dropNonFinite;
        io::WriteOptions wo;
        wo.compress = !o->noCompress;
        const std::vector<size_t> picked = shardOf(jobs, o->sequence.shard);
        SequenceRun run(o->sequence, o->quiet);
        Progress bar(picked.size(), "convert", o->quiet);
        for (size_t k = 0; k < picked.size(); ++k) {
            const FrameJob& job = jobs[picked[k]];
            if (run.skip({job.output})) continue;
            run.frame(job.input, [&] {
                bar.update(k, job.input);
                io::ReadInfo ri;
                const ParticleSet ps = io::readParticles(job.input, ro, &ri);
                io::writeParticles(ps, job.output, wo);
                if (!o->quiet && !bar.enabled()) {
                    std::printf("%s -> %s: %zu particles", job.input.c_str(), job.output.c_str(),
                                ps.size());
                    if (ri.droppedNonFinite)
                        std::printf(" (%zu non-finite dropped)", ri.droppedNonFinite);
                    std::printf("\n");
                }
            });
        }
        bar.finish();
        return run.finish("convert", picked.size());
    };
}

} // namespace cli
} // namespace fluidsurf
