// ParticleFrames.h - the frame loop of the commands that start from particles (rasterize,
// reconstruct): the planned frames less the finished ones, through read, make and write at once
// (runFrameStages, fluidsurf/Sequence.h). Each frame in flight has its own context (a timing
// tree per frame) and carries its particles, params and result from read to write. A frame's
// error waits in its slot for write, which sees the frames in order: --keep-going, the lines
// and the reports come as in a run of one frame after the other.
#pragma once

#include "Frames.h"
#include "Options.h"
#include "Progress.h"
#include "Sequence.h"

#include <fluidsurf/Sequence.h>

#include <algorithm>
#include <exception>
#include <functional>
#include <string>
#include <vector>

namespace fluidsurf {
namespace cli {

double secondsNow();

/// --in-flight N: frames of a sequence under way at once (0: framesInFlight chooses).
void addInFlightOption(CLI::App* cmd, size_t& inFlight);
/// The option's value, or without one: 4 (two frames made at once) where the run has 8 or more
/// threads (-j, else the cores it may use), else 3.
size_t framesInFlight(size_t option, int threads);

template <typename Result> struct ParticleFrame
{
    Context ctx;
    size_t job = 0; ///< position in the jobs
    io::ReadInfo readInfo;
    ParticleSet particles;
    ReconstructParams params; ///< the run's, with the sequence's r
    Result result;
    std::exception_ptr error;
    double stageEnd = 0, waited = 0; ///< seconds: the frame's last stage ended; its waits
};

/// What the loop shares with its command.
struct ParticleRun
{
    const PipelineOptions& options;
    const std::vector<FrameJob>& jobs;
    std::vector<size_t> todo; ///< positions in jobs to run, in order
    io::ReadOptions read;
    ReconstructParams& params; ///< params.radius is set from the first frame read without -r
    size_t inFlight;           ///< --in-flight (0: framesInFlight chooses)
    SequenceRun& run;
    Progress& bar;
};

/// Runs every frame of r.todo: read (and r chosen), make, then write inside SequenceRun::frame
/// (with its error, if an earlier stage failed, raised there). make runs on a frame alone;
/// write runs in frame order, one at a time.
template <typename Result>
void runParticleFrames(ParticleRun& r, const std::function<void(ParticleFrame<Result>&)>& make,
                       const std::function<void(ParticleFrame<Result>&)>& write)
{
    using Frame = ParticleFrame<Result>;
    std::vector<Frame> slots(std::min(std::max<size_t>(r.todo.size(), 1),
                                      framesInFlight(r.inFlight, r.options.threads)));
    auto attempt = [&](Frame& f, auto&& work) {
        if (f.error) return;
        try {
            forFile(r.jobs[f.job].input, work);
        } catch (const Cancelled&) {
            throw;
        } catch (...) {
            f.error = std::current_exception();
        }
    };
    bool radiusChosen = false;
    FrameStages stages;
    stages.read = [&](size_t k, size_t s) {
        Frame& f = slots[s];
        r.options.configure(f.ctx);
        f.job = r.todo[k], f.error = nullptr;
        if (!radiusChosen && f.job != 0) {
            chooseSequenceRadiusFrom(r.options, f.ctx, r.jobs[0], r.read, r.params);
            radiusChosen = true;
        }
        attempt(f, [&] {
            f.particles = readFrame(r.options, f.ctx, r.jobs[f.job].input, r.read, f.readInfo,
                                    !radiusChosen, r.params);
            radiusChosen = true;
        });
        f.params = r.params;
        f.waited = 0, f.stageEnd = secondsNow();
    };
    stages.make = [&](size_t, size_t s) {
        Frame& f = slots[s];
        f.waited += secondsNow() - f.stageEnd;
        attempt(f, [&] { make(f); });
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
            write(f);
        });
        f.particles = ParticleSet(), f.result = Result();
    };
    runFrameStages(r.todo.size(), stages, slots.size());
}

} // namespace cli
} // namespace fluidsurf
