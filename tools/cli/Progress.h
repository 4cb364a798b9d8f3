// Progress.h - a one-line progress bar on stderr when stderr is a terminal, silent when piped
// (logs and CI stay clean).
#pragma once

#include <chrono>
#include <string>

namespace fluidsurf {
namespace cli {

class Progress
{
public:
    Progress(size_t total, std::string label, bool quiet = false);
    ~Progress();
    void update(size_t done, const std::string& item = "");
    void finish();
    bool enabled() const { return mEnabled; }

private:
    size_t mTotal;
    std::string mLabel;
    bool mEnabled;
    bool mFinished = false;
    std::chrono::steady_clock::time_point mStart;
};

} // namespace cli
} // namespace fluidsurf
