// SequenceBench.cc - `fluidsurf_bench sequence`: frames per second of a sequence surfaced by
// `fluidsurf reconstruct` one process per frame (what a shell loop or a farm task per frame
// does) against one process for the whole sequence, with 1, 2, 3 or more frames in flight.
// Whole processes of the CLI next to this program, timed from spawn to exit, with each one's
// peak RSS; every way runs once per round, so that a slow spell weighs on all of them.
#include "Bench.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/Scenes.h>
#include <fluidsurf/io/ParticleIO.h>

#include <tbb/info.h>

#include <spawn.h>
#include <sys/resource.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <sstream>

extern char** environ;

namespace fluidsurf {
namespace bench {

namespace {

/// The fluidsurf program beside this one.
std::string besideThisProgram(const std::string& name)
{
    char path[4096];
    const ssize_t n = readlink("/proc/self/exe", path, sizeof(path) - 1);
    if (n <= 0) return name;
    std::string self(path, size_t(n));
    return self.substr(0, self.rfind('/') + 1) + name;
}

} // namespace

ProcessRun runProcess(const std::vector<std::string>& argv)
{
    std::vector<char*> args;
    for (const std::string& a : argv)
        args.push_back(const_cast<char*>(a.c_str()));
    args.push_back(nullptr);
    ProcessRun run;
    pid_t pid = 0;
    int status = 0;
    rusage usage{};
    run.seconds = seconds([&] {
        if (posix_spawn(&pid, args[0], nullptr, nullptr, args.data(), environ) != 0)
            throw Error("cannot start " + argv[0]);
        wait4(pid, &status, 0, &usage);
    });
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0) {
        std::string line;
        for (const std::string& a : argv)
            line += a + " ";
        throw Error("failed: " + line);
    }
    run.peakMiB = double(usage.ru_maxrss) / 1024.0;
    return run;
}

int runSequenceBench(const SequenceBenchOptions& o)
{
    const std::string cli = o.fluidsurf.empty() ? besideThisProgram("fluidsurf") : o.fluidsurf;
    const std::string dir = o.dir + "/fluidsurf_bench_sequence";
    ::mkdir(dir.c_str(), 0755);
    // The frames: the drop scene, one seed per frame (the droplets move).
    for (int f = 1; f <= o.frames; ++f) {
        SceneParams sp;
        sp.count = o.count, sp.radius = o.radius, sp.seed = unsigned(f);
        char name[64];
        std::snprintf(name, sizeof(name), "/in_%04d.%s", f, o.format.c_str());
        io::writeParticles(generateScene(Scene::Drop, sp), dir + name);
    }
    std::vector<std::string> extra;
    std::istringstream words(o.args);
    for (std::string w; words >> w;)
        extra.push_back(w);
    const std::string r = std::to_string(o.radius);
    auto command = [&](const std::string& in, const std::string& out) {
        std::vector<std::string> argv = {cli, "reconstruct", in, "-r", r, "-o", out, "-q"};
        argv.insert(argv.end(), extra.begin(), extra.end());
        return argv;
    };
    struct Way
    {
        std::string name;
        int inFlight; ///< 0: one process per frame
        std::vector<double> seconds;
        double peakMiB = 0;
    };
    std::vector<Way> ways = {{"one process per frame", 0, {}}};
    for (const std::string& n : split(o.inFlight))
        ways.push_back({"one process, --in-flight " + n, std::stoi(n), {}});
    const std::string pattern = dir + "/in_{:04}." + o.format, out = dir + "/out_{:04}.ply";
    for (int round = 0; round < o.repeat; ++round)
        for (Way& w : ways) {
            ProcessRun all;
            if (w.inFlight == 0) {
                for (int f = 1; f <= o.frames; ++f) {
                    char in[64], res[64];
                    std::snprintf(in, sizeof(in), "/in_%04d.", f);
                    std::snprintf(res, sizeof(res), "/out_%04d.ply", f);
                    const ProcessRun one = runProcess(command(dir + in + o.format, dir + res));
                    all.seconds += one.seconds, all.peakMiB = std::max(all.peakMiB, one.peakMiB);
                }
            } else {
                std::vector<std::string> argv = command(pattern, out);
                argv.insert(argv.end(), {"--in-flight", std::to_string(w.inFlight)});
                all = runProcess(argv);
            }
            w.seconds.push_back(all.seconds), w.peakMiB = std::max(w.peakMiB, all.peakMiB);
        }
    for (int f = 1; f <= o.frames; ++f) {
        char name[64];
        std::snprintf(name, sizeof(name), "/in_%04d.", f);
        std::remove((dir + name + o.format).c_str());
        std::snprintf(name, sizeof(name), "/out_%04d.ply", f);
        std::remove((dir + name).c_str());
    }
    ::rmdir(dir.c_str());
    std::printf("fluidsurf_bench sequence: %d hardware threads; %d frames of the drop scene, "
                "%zu particles asked for, r = %g, .%s to binary .ply; `fluidsurf reconstruct "
                "-q %s`; seconds are medians of %d rounds (each round runs every way once)\n\n",
                tbb::info::default_concurrency(), o.frames, o.count, o.radius, o.format.c_str(),
                o.args.c_str(), o.repeat);
    std::printf("| way | s for %d frames | frames/s | x one process per frame | peak RSS MiB |\n"
                "|---|---|---|---|---|\n",
                o.frames);
    const double base = median(ways[0].seconds);
    for (const Way& w : ways) {
        const double s = median(w.seconds);
        std::printf("| %s | %.2f | %.2f | %.2fx | %.0f |\n", w.name.c_str(), s, o.frames / s,
                    base / s, w.peakMiB);
    }
    return 0;
}

} // namespace bench
} // namespace fluidsurf
