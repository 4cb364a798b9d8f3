// FramesInFlight.h - the frame loop of every command that reads a file, makes something of it
// and writes it (rasterize, reconstruct, mesh, post): the planned frames less the finished ones,
// through read, make and write at once (runFrameStages, fluidsurf/Sequence.h). Each frame in
// flight has its own context (a timing tree per frame) and carries its data from read to write.
// A frame's error waits in its slot for write, which sees the frames in order: --keep-going,
// the lines and the reports come as in a run of one frame after the other.
#pragma once

#include "Frames.h"
#include "Options.h"
#include "Progress.h"
#include "Sequence.h"

#include <fluidsurf/Sequence.h>

#include <tbb/info.h>

#include <algorithm>
#include <chrono>
#include <exception>
#include <functional>
#include <string>
#include <vector>

namespace fluidsurf {
namespace cli {

/// Seconds on the steady clock: a frame's waits between its stages.
inline double secondsNow()
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

/// --in-flight N: frames of a sequence under way at once (0: framesInFlight chooses).
inline void addInFlightOption(CLI::App* cmd, size_t& inFlight)
{
    cmd->add_option("--in-flight", inFlight,
                    "frames of a sequence under way at once: 3 reads frame k+1 and writes frame "
                    "k-1 while frame k is made; 4 to 8 also make frames at once (each frame in "
                    "flight holds its particles and results); 1 runs one frame after the other "
                    "(least memory). Default: 4 with 8 or more threads (-j), else 3")
        ->check(CLI::Range(1, 8));
}

/// The option's value, or without one: 4 (two frames made at once) where the run has 8 or more
/// threads (-j, else the cores it may use), else 3.
inline size_t framesInFlight(size_t option, int threads)
{
    // One frame leaves many cores partly idle (its serial steps, its smaller passes): on 16
    // cores two frames made at once run 1.7x the frames per second of one (BENCHMARKS.md).
    if (option > 0) return option;
    const int cores = tbb::info::default_concurrency(); // the cores this process may use
    return (threads > 0 ? std::min(threads, cores) : cores) >= 8 ? 4 : 3;
}

/// A frame's own work, seconds: its timing tree's total less its waits for the frames before it
/// (call after ctx.timing().finish()).
inline double frameSeconds(const Context& ctx)
{
    return ctx.timing().root().seconds - ctx.timing().seconds("waiting");
}

/// What every frame in flight has; a command's frame type adds its data.
struct FrameInFlight
{
    Context ctx;
    size_t job = 0; ///< position in the jobs
    std::exception_ptr error;
    double stageEnd = 0, waited = 0; ///< seconds: the frame's last stage ended; its waits
};

/// What the loop shares with its command.
struct FrameRun
{
    const PipelineOptions& options;
    const std::vector<FrameJob>& jobs;
    std::vector<size_t> todo; ///< positions in jobs to run, in order
    size_t inFlight;          ///< --in-flight (0: framesInFlight chooses)
    SequenceRun& run;
    Progress& bar;
};

/// The steps of one frame. prepare (optional) runs before read, outside the frame's errors:
/// what it throws stops the run. read and make run on a frame alone; write runs in frame order,
/// one at a time, inside SequenceRun::frame (with the frame's error, if an earlier step failed,
/// raised there). After write the slot is emptied (Frame{} but for its context).
template <typename Frame> struct FrameSteps
{
    std::function<void(Frame&)> prepare, read, make, write, clear;
};

template <typename Frame> void runFramesInFlight(FrameRun& r, const FrameSteps<Frame>& steps)
{
    std::vector<Frame> slots(std::min(std::max<size_t>(r.todo.size(), 1),
                                      framesInFlight(r.inFlight, r.options.threads)));
    auto attempt = [&](Frame& f, const std::function<void(Frame&)>& step) {
        if (f.error) return;
        try {
            forFile(r.jobs[f.job].input, [&] { step(f); });
        } catch (const Cancelled&) {
            throw;
        } catch (...) {
            f.error = std::current_exception();
        }
    };
    FrameStages stages;
    stages.read = [&](size_t k, size_t s) {
        Frame& f = slots[s];
        r.options.configure(f.ctx);
        f.ctx.setFramesInRun(r.todo.size()); // (Device::Auto's rule: one context serves them)
        f.ctx.timing().clear();
        f.job = r.todo[k], f.error = nullptr;
        if (steps.prepare) steps.prepare(f);
        attempt(f, steps.read);
        f.waited = 0, f.stageEnd = secondsNow();
    };
    stages.make = [&](size_t, size_t s) {
        Frame& f = slots[s];
        f.waited += secondsNow() - f.stageEnd;
        attempt(f, steps.make);
        f.stageEnd = secondsNow();
    };
    stages.write = [&](size_t k, size_t s) {
        Frame& f = slots[s];
        f.waited += secondsNow() - f.stageEnd;
        // Between its stages a frame waits for the frames before it: shown apart, so that the
        // frame's line gives its own work.
        if (slots.size() > 1) f.ctx.timing().add("waiting", f.waited);
        r.bar.update(k, r.jobs[f.job].input);
        r.run.frame(r.jobs[f.job].input, [&] {
            if (f.error) std::rethrow_exception(f.error);
            steps.write(f);
        });
        steps.clear(f);
    };
    runFrameStages(r.todo.size(), stages, slots.size());
}

} // namespace cli
} // namespace fluidsurf
