// Frames.cc
#include "Frames.h"

#include <fluidsurf/Error.h>

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

} // namespace cli
} // namespace fluidsurf
