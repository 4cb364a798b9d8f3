// Context.cc - the timing tree, checkpoints and device names: what every stage receives beside
// its data (fluidsurf/Context.h). Below every stage, so stages depend on it and never on the
// pipeline that runs them.
#include <fluidsurf/Context.h>
#include <fluidsurf/Error.h>
#include <fluidsurf/MemoryBudget.h>

#include <tbb/info.h>

#include <sys/resource.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cstdint>
#include <cstdio>
#include <functional>

namespace fluidsurf {

namespace {
double now()
{
    return std::chrono::duration<double>(std::chrono::steady_clock::now().time_since_epoch())
        .count();
}

std::string jsonString(const std::string& s)
{
    std::string out = "\"";
    for (const char c : s) {
        if (c == '"' || c == '\\')
            out += '\\', out += c;
        else if (static_cast<unsigned char>(c) < 0x20) {
            char buf[8];
            std::snprintf(buf, sizeof(buf), "\\u%04x", c);
            out += buf;
        } else
            out += c;
    }
    return out + "\"";
}
} // namespace

double peakMemoryMiB()
{
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_maxrss) / 1024.0;
}

const char* deviceName(Device d)
{
    return d == Device::Cpu ? "cpu" : d == Device::Cuda ? "cuda" : "auto";
}

Device deviceFromName(const std::string& name)
{
    if (name == "cpu") return Device::Cpu;
    if (name == "cuda") return Device::Cuda;
    if (name == "auto") return Device::Auto;
    throw ValueError("unknown device '" + name + "' (cpu, cuda, auto)");
}

// --- TimingTree ----------------------------------------------------------------------------

TimingTree::TimingTree()
{
    clear();
}

void TimingTree::clear()
{
    mNodes.assign(1, Node{});
    mNodes[0].name = "total";
    mOpen = 0;
    mStart = now();
}

void TimingTree::finish()
{
    mNodes[0].seconds = now() - mStart;
    mNodes[0].peakMiB = peakMemoryMiB();
}

TimingTree::Scope::Scope(TimingTree& tree, const std::string& name)
    : mTree(tree), mNode(tree.mNodes.size()), mStart(now())
{
    Node n;
    n.name = name;
    n.parent = tree.mOpen;
    tree.mNodes.push_back(std::move(n));
    tree.mNodes[tree.mOpen].children.push_back(mNode);
    tree.mOpen = mNode;
}

TimingTree::Scope::~Scope()
{
    Node& n = mTree.mNodes[mNode];
    n.seconds = now() - mStart;
    n.peakMiB = peakMemoryMiB();
    mTree.mOpen = n.parent;
}

void TimingTree::add(const std::string& name, double seconds)
{
    Node n;
    n.name = name;
    n.seconds = seconds;
    n.parent = mOpen;
    n.peakMiB = peakMemoryMiB();
    mNodes[mOpen].children.push_back(mNodes.size());
    mNodes.push_back(std::move(n));
}

double TimingTree::seconds(const std::string& name) const
{
    for (const Node& n : mNodes)
        if (n.name == name) return n.seconds;
    return 0;
}

bool TimingTree::has(const std::string& name) const
{
    for (size_t i = 1; i < mNodes.size(); ++i)
        if (mNodes[i].name == name) return true;
    return false;
}

std::string TimingTree::format() const
{
    const double total = mNodes[0].seconds > 0 ? mNodes[0].seconds : 1;
    std::string out;
    char line[160];
    std::function<void(size_t, int)> print = [&](size_t i, int depth) {
        const Node& n = mNodes[i];
        const std::string label = std::string(size_t(2 * depth), ' ') + n.name;
        std::snprintf(line, sizeof(line), "  %-28s %9.4f s %6.1f%%  %8.1f MiB\n", label.c_str(),
                      n.seconds, 100 * n.seconds / total, n.peakMiB);
        out += line;
        for (size_t c : n.children)
            print(c, depth + 1);
    };
    std::snprintf(line, sizeof(line), "  %-28s %11s %7s  %12s\n", "stage", "time", "share",
                  "peak memory");
    out += line;
    print(0, 0);
    return out;
}

std::string TimingTree::toJson() const
{
    std::function<std::string(size_t)> node = [&](size_t i) {
        const Node& n = mNodes[i];
        char num[96];
        std::snprintf(num, sizeof(num), ", \"seconds\": %.6f, \"peak_mib\": %.1f", n.seconds,
                      n.peakMiB);
        std::string s = "{\"name\": " + jsonString(n.name) + num + ", \"children\": [";
        for (size_t k = 0; k < n.children.size(); ++k)
            s += (k ? ", " : "") + node(n.children[k]);
        return s + "]}";
    };
    return node(0);
}

// --- Context -------------------------------------------------------------------------------

void Context::setThreads(int n)
{
    if (n < 0 || n > kMaxThreads)
        throw ValueError("threads = " + std::to_string(n) + ": between 0 (all cores) and " +
                         std::to_string(kMaxThreads) + " expected");
    mThreads = n;
}

int Context::runThreads() const
{
    const int cores = tbb::info::default_concurrency(); // (affinity and cgroup limits too)
    return mThreads > 0 ? std::min(mThreads, cores) : cores;
}

namespace {
std::atomic<size_t> gProcessBudget{0};
} // namespace

size_t processMemoryBudget()
{
    if (const size_t set = gProcessBudget.load()) return set;
    const double physical = double(::sysconf(_SC_PHYS_PAGES)) * double(::sysconf(_SC_PAGE_SIZE));
    return physical > 0 ? size_t(0.8 * physical) : SIZE_MAX;
}

void setProcessMemoryBudget(size_t bytes)
{
    gProcessBudget.store(bytes);
}

void requireMemory(double bytes, const std::string& what, size_t budget)
{
    const bool given = budget > 0 || gProcessBudget.load() > 0;
    if (budget == 0) budget = processMemoryBudget();
    if (!(bytes > double(budget))) return;
    char text[200];
    std::snprintf(text, sizeof(text),
                  " needs about %.0f MiB, more than the memory budget of %.0f MiB (%s)",
                  bytes / 1048576.0, double(budget) / 1048576.0,
                  given ? "--max-memory" : "80% of this machine's memory; --max-memory");
    throw ValueError(what + text);
}

size_t Context::memoryBudget() const
{
    return mMemoryBudget > 0 ? mMemoryBudget : processMemoryBudget();
}

void Context::requireMemory(double bytes, const std::string& what) const
{
    fluidsurf::requireMemory(bytes, what, mMemoryBudget); // (0: the process's, said so)
}

void Context::checkpoint()
{
    if (mCancelled.load(std::memory_order_relaxed)) throw Cancelled();
    // Without a callback a checkpoint is one relaxed load: nothing shared is written in the
    // stages' inner loops.
    if (!mProgress) return;
    const size_t ranges = mRanges.load(std::memory_order_relaxed);
    {
        // One call at a time; a thread that finds the callback busy goes on and sees a stop at
        // its next range. A thread that gets the lock just after the call that said stop sees
        // the stop here (it was stored under the lock): the callback is never called again.
        // (Checked only before the lock, a 7th call came after a 6th said stop, once in a
        // while on 16 cores.)
        std::unique_lock<std::mutex> lock(mProgressMutex, std::try_to_lock);
        if (lock.owns_lock() && !mCancelled.load() &&
            !mProgress(ProgressEvent{mTiming.current(), ranges}))
            mCancelled.store(true);
    }
    if (mCancelled.load()) throw Cancelled();
    mRanges.fetch_add(1, std::memory_order_relaxed); // only ranges that go on are counted
}

void Context::throwIfCancelled() const
{
    if (mCancelled.load()) throw Cancelled();
}

void Context::reset()
{
    mCancelled.store(false);
    mRanges.store(0);
}

} // namespace fluidsurf
