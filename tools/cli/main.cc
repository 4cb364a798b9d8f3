// main.cc - the fluidsurf command line: parse, dispatch to a subcommand, turn exceptions into
// one message on stderr and a non-zero exit code.
#include "Commands.h"
#include "Options.h"
#include "ProcessMemory.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Version.h>

#include <tbb/task_arena.h>

#include <iostream>
#include <string>

namespace {

/// The message as one line of UTF-8 text: names read from a corrupt file can hold newlines,
/// terminal escapes or bytes that are not text. Anything else becomes '?'.
std::string oneLine(const std::string& s)
{
    std::string out;
    for (size_t i = 0; i < s.size();) {
        const unsigned char c = static_cast<unsigned char>(s[i]);
        const size_t len = c < 0x80           ? 1
                           : (c >> 5) == 0x6  ? 2
                           : (c >> 4) == 0xE  ? 3
                           : (c >> 3) == 0x1E ? 4
                                              : 0;
        bool ok = len > 0 && i + len <= s.size() && !(len == 1 && (c < 0x20 || c == 0x7f));
        for (size_t k = 1; ok && k < len; ++k)
            ok = (static_cast<unsigned char>(s[i + k]) & 0xC0) == 0x80;
        if (ok) {
            out.append(s, i, len);
            i += len;
        } else {
            out += '?';
            ++i;
        }
    }
    return out;
}

} // namespace

int main(int argc, char** argv)
{
    using namespace fluidsurf;
    cli::setUpProcessMemory(argv); // first: before the stages allocate
    // TBB's workers asked for now, while the command line is read: they come one after
    // another, and the first parallel loop (a raw .xyz read's page faults) ran on a few threads
    // while they did. On an H100 host's 16 threads the 13.1M drop's 157 MB of positions
    // faulted in in 24-47 ms, in 4-16 ms with this (6 runs each).
    tbb::this_task_arena::enqueue([] {});
    CLI::App app{"fluidsurf " FLUIDSURF_VERSION_STRING
                 " - SPH particle frames to OpenVDB level sets and triangle meshes"};
    app.set_version_flag("--version", std::string("fluidsurf ") + FLUIDSURF_VERSION_STRING);
    app.require_subcommand(1);
    app.footer(R"(Examples:
  fluidsurf info frame.bgeo                      what a particle file holds, and its radius
  fluidsurf convert frame.vtk frame.vdb          particles to OpenVDB points
  fluidsurf convert 'sim/f_{:04}.bgeo' 'out/f_{:04}.ply' --frames 1-100
  fluidsurf generate drop --count 100000 -o drop.bgeo
  fluidsurf rasterize frame.bgeo -r 0.025 -o frame.vdb   narrow-band level set
  fluidsurf mesh frame.vdb -o frame.obj                  level set to mesh
  fluidsurf reconstruct frame.bgeo -r 0.025 -o frame.obj particles to mesh
  fluidsurf post frame.obj -o smooth.obj                 Loop subdivision of a mesh

Frame sequences: {:04}, #### or %04d in a file name; --frames A-B picks frames,
otherwise every matching file on disk is used.
Run 'fluidsurf COMMAND --help' for the options of a command.)");
    const cli::Runner info = cli::addInfoCommand(app);
    const cli::Runner convert = cli::addConvertCommand(app);
    const cli::Runner generate = cli::addGenerateCommand(app);
    const cli::Runner rasterize = cli::addRasterizeCommand(app);
    const cli::Runner mesh = cli::addMeshCommand(app);
    const cli::Runner reconstruct = cli::addReconstructCommand(app);
    const cli::Runner post = cli::addPostCommand(app);
    try {
        app.parse(argc, argv);
    } catch (const CLI::CallForHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForAllHelp& e) {
        return app.exit(e);
    } catch (const CLI::CallForVersion& e) {
        return app.exit(e);
    } catch (const CLI::ParseError& e) {
        std::cerr << "fluidsurf: error: " << oneLine(e.what()) << " (see 'fluidsurf --help')\n";
        return e.get_exit_code() ? e.get_exit_code() : 2;
    }
    cli::installInterruptHandler();
    const auto runCommand = [&]() -> int {
        try {
            if (app.got_subcommand("info")) return info();
            if (app.got_subcommand("convert")) return convert();
            if (app.got_subcommand("generate")) return generate();
            if (app.got_subcommand("rasterize")) return rasterize();
            if (app.got_subcommand("mesh")) return mesh();
            if (app.got_subcommand("reconstruct")) return reconstruct();
            if (app.got_subcommand("post")) return post();
        } catch (const fluidsurf::Cancelled&) {
            // Ctrl-C: outputs are written through temporary files, so nothing partial is left.
            std::cerr << "fluidsurf: interrupted; no partial output was written\n";
            return cli::interruptExitCode();
        } catch (const fluidsurf::Error& e) {
            std::cerr << "fluidsurf: error: " << oneLine(e.what()) << "\n";
            return 1;
        } catch (const std::bad_alloc&) {
            std::cerr << "fluidsurf: error: out of memory\n";
            return 1;
        } catch (const std::exception& e) {
            std::cerr << "fluidsurf: error: " << oneLine(e.what()) << "\n";
            return 1;
        }
        return 2;
    };
    const int code = runCommand();
    // Before exit's handlers run: an exit that begins while the CUDA context is being made (a
    // bad input fails in milliseconds) can hang for good (Rasterize.h).
    waitForDevice();
    return code;
}
