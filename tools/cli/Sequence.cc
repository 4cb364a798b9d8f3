// Sequence.cc
#include "Sequence.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/io/LevelSetIO.h>
#include <fluidsurf/io/MeshIO.h>
#include <fluidsurf/io/ParticleIO.h>

#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <string>

namespace fluidsurf {
namespace cli {

namespace {

/// A whole number from text, or -1 when it is not one (or out of range).
long wholeNumber(const std::string& text)
{
    if (text.empty() || text.size() > 9) return -1;
    for (const char c : text)
        if (c < '0' || c > '9') return -1;
    return std::strtol(text.c_str(), nullptr, 10);
}

/// One line of an error message (the CLI prints each error on one line).
std::string firstLine(const std::string& text)
{
    const size_t end = text.find('\n');
    return end == std::string::npos ? text : text.substr(0, end);
}

bool endsWith(const std::string& s, const char* tail)
{
    const size_t n = std::char_traits<char>::length(tail);
    return s.size() >= n && s.compare(s.size() - n, n, tail) == 0;
}

/// Whether an existing output reads back whole with our own reader for its name: a zero-byte
/// or truncated file (another tool's, a copy cut short, a disk that filled before this version
/// checked every write) is not a finished frame. A read costs far less than the frame.
bool readsBackWhole(const std::string& path)
{
    struct stat st;
    if (::stat(path.c_str(), &st) != 0 || !S_ISREG(st.st_mode) || st.st_size == 0) return false;
    try {
        if (endsWith(path, ".vdb")) {
            io::describeVdb(path);
            return true;
        }
        if (endsWith(path, ".json")) return true;
        if (io::meshFormatFromPath(path) != io::MeshFormat::Unknown) {
            try {
                io::readMesh(path);
                return true;
            } catch (const InputError&) {
                // .ply and .vtk may hold particles (convert): tried as such below
            }
        }
        if (io::formatFromPath(path) == io::ParticleFormat::Unknown) return true; // none to try
        io::readParticles(path);
        return true;
    } catch (const Error&) {
        return false;
    }
}

} // namespace

void addSequenceOptions(CLI::App* cmd, SequenceOptions& o)
{
    cmd->add_option("--shard", o.shard,
                    "run a share of a sequence's frames: I/N takes every N-th frame from the "
                    "I-th (1 <= I <= N); slurm takes the frame numbered $SLURM_ARRAY_TASK_ID "
                    "(sbatch --array=FIRST-LAST)");
    cmd->add_flag("--skip-existing", o.skipExisting,
                  "leave out frames whose outputs all exist and read back whole (a re-run after "
                  "a failure or a time limit); outputs are written whole or not at all");
    cmd->add_flag("--keep-going", o.keepGoing,
                  "a frame that fails (corrupt, missing) is reported and left out, and the run "
                  "goes on; it ends with the list of failed frames and exit code 1 (default: "
                  "stop at the first error)");
}

std::vector<size_t> shardOf(const std::vector<FrameJob>& jobs, const std::string& shard)
{
    std::vector<size_t> picked;
    if (shard.empty()) {
        for (size_t i = 0; i < jobs.size(); ++i)
            picked.push_back(i);
        return picked;
    }
    if (jobs.size() == 1 && jobs[0].frame < 0)
        throw ValueError("--shard needs a frame pattern ({:04}, ####, %04d), not a single file");
    if (shard == "slurm") {
        const char* id = std::getenv("SLURM_ARRAY_TASK_ID");
        if (!id)
            throw ValueError("--shard slurm: SLURM_ARRAY_TASK_ID is not set (run it in an array "
                             "job: sbatch --array=FIRST-LAST)");
        const long frame = wholeNumber(id);
        if (frame < 0)
            throw ValueError("--shard slurm: SLURM_ARRAY_TASK_ID '" + std::string(id) +
                             "' is not a frame number");
        for (size_t i = 0; i < jobs.size(); ++i)
            if (jobs[i].frame == frame) return {i};
        throw ValueError("--shard slurm: frame " + std::to_string(frame) +
                         " (SLURM_ARRAY_TASK_ID) is not in the sequence (frames " +
                         std::to_string(jobs.front().frame) + "-" +
                         std::to_string(jobs.back().frame) + ")");
    }
    const size_t slash = shard.find('/');
    const long i = slash == std::string::npos ? -1 : wholeNumber(shard.substr(0, slash));
    const long n = slash == std::string::npos ? -1 : wholeNumber(shard.substr(slash + 1));
    if (i < 1 || n < 1 || i > n)
        throw ValueError("bad --shard '" + shard +
                         "': expected I/N with 1 <= I <= N (e.g. 2/8), or slurm");
    for (size_t k = size_t(i - 1); k < jobs.size(); k += size_t(n))
        picked.push_back(k);
    return picked;
}

void chooseSequenceRadiusFrom(const PipelineOptions& po, Context& ctx, const FrameJob& first,
                              const io::ReadOptions& read, ReconstructParams& params)
{
    if (po.params.radius > 0) {
        params.radius = po.params.radius;
        return;
    }
    try {
        io::ReadInfo info;
        readFrame(po, ctx, first.input, read, info, true, params);
    } catch (const Cancelled&) {
        throw;
    } catch (const Error& e) {
        throw ValueError("r is chosen from the sequence's first frame, which cannot be read (" +
                         firstLine(e.what()) + "); pass -r");
    }
}

SequenceRun::SequenceRun(const SequenceOptions& o, bool quiet)
    : mOptions(o), mQuiet(quiet), mStart(std::chrono::steady_clock::now())
{
}

bool SequenceRun::skip(const std::vector<std::string>& outputs)
{
    if (!mOptions.skipExisting) return false;
    for (const std::string& path : outputs) {
        if (!readsBackWhole(path)) return false;
    }
    ++mSkipped;
    return true;
}

std::vector<size_t>
SequenceRun::unfinished(const std::vector<size_t>& picked,
                        const std::function<std::vector<std::string>(size_t job)>& outputsOf)
{
    std::vector<size_t> todo;
    for (size_t i : picked)
        if (!skip(outputsOf(i))) todo.push_back(i);
    return todo;
}

void SequenceRun::failed(const std::string& input, const std::string& why)
{
    mFailed.emplace_back(input, firstLine(why));
    std::fprintf(stderr, "fluidsurf: error: %s (left out: --keep-going)\n", firstLine(why).c_str());
}

int SequenceRun::finish(const char* verb, size_t planned) const
{
    const bool options = !mOptions.shard.empty() || mOptions.skipExisting || mOptions.keepGoing;
    if ((planned > 1 || options) && !mQuiet) {
        const double secs =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - mStart).count();
        std::printf("%s %zu frame%s: %zu done, %zu skipped, %zu failed, %.2f s\n", verb, planned,
                    planned == 1 ? "" : "s", mDone, mSkipped, mFailed.size(), secs);
    }
    if (!mFailed.empty()) {
        std::fprintf(stderr, "fluidsurf: %zu frame%s failed:\n", mFailed.size(),
                     mFailed.size() == 1 ? "" : "s");
        for (const auto& [input, why] : mFailed)
            std::fprintf(stderr, "  %s\n", input.c_str());
    }
    std::fflush(stdout);
    return mFailed.empty() ? 0 : 1;
}

} // namespace cli
} // namespace fluidsurf
