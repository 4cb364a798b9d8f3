// Progress.cc
#include "Progress.h"

#include <cstdio>
#include <unistd.h>

namespace fluidsurf {
namespace cli {

Progress::Progress(size_t total, std::string label, bool quiet)
    : mTotal(total), mLabel(std::move(label)), mEnabled(!quiet && total > 1 && ::isatty(2)),
      mStart(std::chrono::steady_clock::now())
{
}

Progress::~Progress()
{
    finish();
}

void Progress::update(size_t done, const std::string& item)
{
    if (!mEnabled) return;
    const int width = 30;
    const int filled = mTotal ? int(width * done / mTotal) : width;
    const double secs =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - mStart).count();
    const double eta = done ? secs / double(done) * double(mTotal - done) : 0;
    std::fprintf(stderr, "\r%s [%.*s%*s] %zu/%zu  %.1fs elapsed, ~%.0fs left  %.40s\033[K",
                 mLabel.c_str(), filled, "##############################", width - filled, "", done,
                 mTotal, secs, eta, item.c_str());
    std::fflush(stderr);
}

void Progress::finish()
{
    if (!mEnabled || mFinished) return;
    mFinished = true;
    std::fprintf(stderr, "\r\033[K");
    std::fflush(stderr);
}

} // namespace cli
} // namespace fluidsurf
