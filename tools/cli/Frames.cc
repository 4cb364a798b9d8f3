// Frames.cc
#include "Frames.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/io/AtomicFile.h>

#include <sys/stat.h>

#include <algorithm>
#include <cctype>
#include <climits>
#include <cstdlib>
#include <cstring>
#include <map>
#include <set>

namespace fluidsurf {
namespace cli {

std::vector<FrameJob> planFrames(const std::string& input, const std::string& output,
                                 const std::string& range)
{
    const FramePattern in(input);
    const FramePattern out(output.empty() ? std::string("-") : output);
    if (!in.isSequence()) {
        if (!range.empty())
            throw ValueError("--frames given but '" + input +
                             "' is not a frame pattern ({:04}, ####, %04d)");
        if (out.isSequence())
            throw ValueError("output '" + output + "' is a pattern but the input is a single file");
        return {{input, output, -1}};
    }
    if (!output.empty() && !out.isSequence())
        throw ValueError(
            "input '" + input +
            "' is a sequence, so the output must be a pattern too (e.g. out_{:04}.vdb)");
    const std::vector<int> frames = range.empty() ? in.existingFrames() : parseFrameRange(range);
    if (frames.empty()) throw ValueError("no files match the pattern '" + input + "'");
    std::vector<FrameJob> jobs;
    for (int f : frames)
        jobs.push_back({in.frame(f), output.empty() ? std::string() : out.frame(f), f});
    return jobs;
}

std::vector<FrameJob> planVdbFrames(const std::string& input, const std::string& output,
                                    const std::string& range, const std::string& what)
{
    std::vector<FrameJob> jobs = planFrames(input, output, range);
    for (const FrameJob& job : jobs) {
        const std::string& out = job.output;
        if (out.size() < 4 || out.compare(out.size() - 4, 4, ".vdb") != 0)
            throw ValueError(what + " '" + out + "' must end in .vdb");
    }
    return jobs;
}

namespace {
/// The file a path names: "dev:inode" when it exists, else the real path of its folder plus its
/// name (an output that does not exist yet can only collide with another output).
std::string fileKey(const std::string& path)
{
    struct stat st;
    if (::stat(path.c_str(), &st) == 0)
        return std::to_string(st.st_dev) + ":" + std::to_string(st.st_ino);
    const size_t slash = path.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "." : path.substr(0, slash + 1);
    const std::string name = slash == std::string::npos ? path : path.substr(slash + 1);
    char resolved[PATH_MAX];
    if (::realpath(dir.c_str(), resolved)) return std::string(resolved) + "/" + name;
    return path;
}
} // namespace

void refuseOverwritingInputs(const std::vector<std::string>& inputs,
                             const std::vector<std::string>& outputs)
{
    std::map<std::string, std::string> files;
    for (const std::string& in : inputs)
        files.emplace(fileKey(in), in);
    std::map<std::string, std::string> written;
    for (const std::string& out : outputs) {
        const std::string key = fileKey(out);
        const auto input = files.find(key);
        if (input != files.end())
            throw ValueError("output '" + out + "' is the input '" + input->second +
                             "' of this run; refusing to overwrite an input");
        const auto other = written.emplace(key, out);
        if (!other.second)
            throw ValueError("outputs '" + other.first->second + "' and '" + out +
                             "' are the same file");
    }
}

void refuseUnwritableOutputs(const std::vector<std::string>& outputs)
{
    std::set<std::string> folders; // each once: a sequence's frames share one, as a rule
    for (const std::string& out : outputs) {
        const size_t slash = out.find_last_of('/');
        const std::string folder = slash == std::string::npos ? "." : out.substr(0, slash + 1);
        const bool notAFile = out.empty() || out.back() == '/'; // refused whatever the folder
        if (notAFile || folders.insert(folder).second) io::requireWritableFolder(out);
    }
}

void checkRunFiles(const std::vector<std::string>& inputs, std::vector<std::string> outputs,
                   const std::string& stats)
{
    if (!stats.empty()) outputs.push_back(stats);
    refuseOverwritingInputs(inputs, outputs);
    refuseUnwritableOutputs(outputs);
}

uint64_t inputBytes(const std::vector<FrameJob>& jobs, const std::vector<size_t>& picked)
{
    uint64_t bytes = 0;
    for (size_t i : picked) {
        struct stat st;
        if (i < jobs.size() && ::stat(jobs[i].input.c_str(), &st) == 0 && S_ISREG(st.st_mode))
            bytes += uint64_t(st.st_size);
    }
    return bytes;
}

bool worthPreparingDevice(const Context& ctx, const std::vector<FrameJob>& jobs,
                          const std::vector<size_t>& todo)
{
    if (ctx.device() != Device::Auto) return ctx.device() == Device::Cuda;
    auto endsWith = [](const std::string& s, const char* tail) {
        const size_t n = std::strlen(tail);
        return s.size() >= n && s.compare(s.size() - n, n, tail) == 0;
    };
    uint64_t largest = 0;
    for (size_t i : todo) {
        if (i >= jobs.size()) continue;
        std::string input = jobs[i].input;
        std::transform(input.begin(), input.end(), input.begin(),
                       [](unsigned char c) { return char(std::tolower(c)); });
        for (const char* compressed : {".gz", ".vtu", ".vtp", ".vdb"})
            if (endsWith(input, compressed)) return true;
        struct stat st;
        if (::stat(jobs[i].input.c_str(), &st) != 0) return true; // (its reading says why)
        largest = std::max(largest, uint64_t(st.st_size));
    }
    const double mostParticles = double(largest) / 6 * double(todo.size());
    return mostParticles >= autoGpuParticles(ctx.runThreads());
}

std::vector<std::string> inputsOf(const std::vector<FrameJob>& jobs)
{
    std::vector<std::string> v;
    for (const FrameJob& j : jobs)
        v.push_back(j.input);
    return v;
}

std::vector<std::string> outputsOf(const std::vector<FrameJob>& jobs)
{
    std::vector<std::string> v;
    for (const FrameJob& j : jobs)
        v.push_back(j.output);
    return v;
}

} // namespace cli
} // namespace fluidsurf
