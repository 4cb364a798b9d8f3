// main.cc - fluidsurf_bench: the benchmark program. Prints per-case wall-time medians,
// throughput and peak RSS as a Markdown table (or JSON with --json) for BENCHMARKS.md.
//   fluidsurf_bench io [--count N] [--repeat K]   particle read throughput per format
#include "Bench.h"

#include <CLI/CLI.hpp>

int main(int argc, char** argv)
{
    CLI::App app{"fluidsurf_bench - speed and memory of the fluidsurf stages"};
    app.require_subcommand(1);
    fluidsurf::bench::ReadBenchOptions io;
    CLI::App* ioCmd = app.add_subcommand("io", "particle read throughput per format on a generated frame");
    ioCmd->add_option("--count", io.count, "particles in the generated frame")->capture_default_str();
    ioCmd->add_option("--repeat", io.repeat, "reads per format (median reported)")->capture_default_str();
    ioCmd->add_option("--dir", io.dir, "folder for the temporary files")->capture_default_str();
    ioCmd->add_option("--shared", io.shared, "../shared/data to also time the real frames ('' to skip)")->capture_default_str();
    ioCmd->add_flag("--json", io.json, "JSON instead of a Markdown table");
    CLI11_PARSE(app, argc, argv);
    try {
        if (app.got_subcommand("io")) return fluidsurf::bench::runReadBench(io);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "fluidsurf_bench: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
