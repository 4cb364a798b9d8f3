// Sequence.h - running a frame sequence the way a farm needs it: a share of the frames per task
// (--shard), finished frames left alone (--skip-existing), a bad frame reported and passed over
// (--keep-going), and one summary line at the end. Used by rasterize, reconstruct, mesh and
// post.
#pragma once

#include "Frames.h"
#include "Options.h"

#include <CLI/CLI.hpp>

#include <chrono>
#include <cstddef>
#include <functional>
#include <string>
#include <utility>
#include <vector>

namespace fluidsurf {
namespace cli {

struct SequenceOptions
{
    std::string shard;         ///< "I/N" (1 <= I <= N) or "slurm"; empty: every frame
    bool skipExisting = false; ///< a frame whose outputs all exist is not run again
    bool keepGoing = false;    ///< a failed frame is reported and the run goes on
};

void addSequenceOptions(CLI::App* cmd, SequenceOptions& o);

/// The positions in jobs that this task runs: with "I/N" every N-th from the I-th (frames
/// next to each other cost about the same, so the shares do too); with "slurm" the one frame
/// numbered $SLURM_ARRAY_TASK_ID. ValueError for a malformed share, a single file, a missing or
/// bad SLURM_ARRAY_TASK_ID, or a frame the sequence lacks.
std::vector<size_t> shardOf(const std::vector<FrameJob>& jobs, const std::string& shard);

/// Before the first frame a run reads, when that is not the sequence's first (a shard, or
/// frames skipped or failed): r as a run of the whole sequence chooses it, from the sequence's
/// first frame, so that every task of a farm run meshes with one r. Nothing to read when -r
/// gives it. ValueError naming that frame when it cannot be read.
void chooseSequenceRadiusFrom(const PipelineOptions& po, Context& ctx, const FrameJob& first,
                              const io::ReadOptions& read, ReconstructParams& params);

/// One run over a sequence's frames: counts, failures, time.
class SequenceRun
{
public:
    SequenceRun(const SequenceOptions& o, bool quiet);

    /// With --skip-existing, whether a frame is done already: every one of its outputs exists,
    /// is not empty and reads back whole with our reader for its format (ours are written
    /// whole or not at all; a zero-byte or cut file from elsewhere is made again). Counts it.
    bool skip(const std::vector<std::string>& outputs);
    /// The positions in picked whose frames are not done already (skip), in order.
    std::vector<size_t>
    unfinished(const std::vector<size_t>& picked,
               const std::function<std::vector<std::string>(size_t job)>& outputsOf);

    /// Runs one frame's work. Ctrl-C stops the run. Another error stops it too, unless
    /// --keep-going: then it is printed on stderr at once and listed by finish().
    template <typename F> void frame(const std::string& input, F&& work)
    {
        try {
            forFile(input, work);
            ++mDone;
        } catch (const Cancelled&) {
            throw;
        } catch (const Error& e) {
            if (!mOptions.keepGoing) throw;
            failed(input, e.what());
        }
    }

    /// For a sequence (more than one frame planned) or any of the options: one line, "VERB N
    /// frames: D done, S skipped, F failed, T s" (not with -q), and the failed frames on
    /// stderr. Returns the exit code: 1 when a frame failed, else 0.
    int finish(const char* verb, size_t planned) const;

private:
    void failed(const std::string& input, const std::string& why);

    SequenceOptions mOptions;
    bool mQuiet = false;
    size_t mDone = 0, mSkipped = 0;
    std::vector<std::pair<std::string, std::string>> mFailed; ///< input, message
    std::chrono::steady_clock::time_point mStart;
};

} // namespace cli
} // namespace fluidsurf
