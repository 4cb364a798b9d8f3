// ParticleFrames.h - the frame loop (FramesInFlight.h) of the commands that start from
// particles (rasterize, reconstruct): read chooses the sequence's r from the first frame read
// (without -r), so that neighbouring frames match.
#pragma once

#include "FramesInFlight.h"

namespace fluidsurf {
namespace cli {

template <typename Result> struct ParticleFrame : FrameInFlight
{
    io::ReadInfo readInfo;
    ParticleSet particles;
    ReconstructParams params; ///< the run's, with the sequence's r
    Result result;
};

/// Runs every frame of r.todo: read (and r chosen into params.radius), make, write (see
/// FrameSteps).
template <typename Result>
void runParticleFrames(FrameRun& r, const io::ReadOptions& read, ReconstructParams& params,
                       const std::function<void(ParticleFrame<Result>&)>& make,
                       const std::function<void(ParticleFrame<Result>&)>& write)
{
    using Frame = ParticleFrame<Result>;
    bool radiusChosen = false;
    FrameSteps<Frame> steps;
    steps.prepare = [&](Frame& f) {
        if (!radiusChosen && f.job != 0) {
            chooseSequenceRadiusFrom(r.options, f.ctx, r.jobs[0], read, params);
            radiusChosen = true;
        }
    };
    steps.read = [&](Frame& f) {
        f.particles = readFrame(r.options, f.ctx, r.jobs[f.job].input, read, f.readInfo,
                                !radiusChosen, params);
        radiusChosen = true;
        f.params = params;
    };
    steps.make = make;
    steps.write = write;
    steps.clear = [](Frame& f) { f.particles = ParticleSet(), f.result = Result(); };
    runFramesInFlight(r, steps);
}

} // namespace cli
} // namespace fluidsurf
