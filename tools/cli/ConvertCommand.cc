// ConvertCommand.cc - `fluidsurf convert IN OUT`: particle format conversion, sequences too.
#include "Commands.h"
#include "Frames.h"
#include "Progress.h"

#include <fluidsurf/io/ParticleIO.h>

#include <chrono>
#include <cstdio>
#include <memory>

namespace fluidsurf {
namespace cli {

namespace {
struct ConvertOptions
{
    std::string input, output, frames;
    bool dropNonFinite = false, noCompress = false, quiet = false;
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
                  "drop particles with NaN/Inf coordinates instead of failing");
    cmd->add_flag("--no-compress", o->noCompress, "write VDB points without Blosc compression");
    cmd->add_flag("-q,--quiet", o->quiet, "no progress bar and no per-frame lines");
    cmd->footer("Examples:\n  fluidsurf convert frame.vtk frame.vdb\n"
                "  fluidsurf convert 'sim/f_####.bgeo' 'out/f_####.ply' --frames 1-100");
    return [o]() {
        const auto jobs = planFrames(o->input, o->output, o->frames);
        refuseOverwritingInputs(inputsOf(jobs), outputsOf(jobs));
        io::ReadOptions ro;
        ro.dropNonFinite = o->dropNonFinite;
        io::WriteOptions wo;
        wo.compress = !o->noCompress;
        Progress bar(jobs.size(), "convert", o->quiet);
        size_t total = 0;
        const auto start = std::chrono::steady_clock::now();
        for (size_t i = 0; i < jobs.size(); ++i) {
            bar.update(i, jobs[i].input);
            io::ReadInfo ri;
            const ParticleSet ps = io::readParticles(jobs[i].input, ro, &ri);
            io::writeParticles(ps, jobs[i].output, wo);
            total += ps.size();
            if (!o->quiet && !bar.enabled()) {
                std::printf("%s -> %s: %zu particles", jobs[i].input.c_str(),
                            jobs[i].output.c_str(), ps.size());
                if (ri.droppedNonFinite)
                    std::printf(" (%zu non-finite dropped)", ri.droppedNonFinite);
                std::printf("\n");
            }
        }
        bar.finish();
        const double secs =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        if (jobs.size() > 1)
            std::printf("converted %zu frame(s), %zu particles in %.2f s\n", jobs.size(), total,
                        secs);
        return 0;
    };
}

} // namespace cli
} // namespace fluidsurf
