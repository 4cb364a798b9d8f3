// Context.h - what every stage receives beside its data (DESIGN.md, "Contexts and levels"):
// where the field runs (the backend), how many threads, the timing tree, and the progress /
// cancel callback. One Context serves a whole reconstruction (or a sequence of them); stages
// never read global flags.
//
// Cancelling follows OpenVDB's interrupter pattern: every parallel stage calls checkpoint() once
// per leaf (or particle) range; when the callback has returned false, each thread stops at its
// next range and the run throws Cancelled. Nothing is written by a cancelled run (outputs are
// written through temporary files).
#pragma once

#include <fluidsurf/Error.h>

#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

namespace fluidsurf {

/// Where the field is computed. Cuda runs the narrow band on the first GPU (sort, classify, band,
/// gather; gather-full only gathers there); Auto picks Cuda when the library was built with CUDA,
/// a usable GPU is present and the run is large enough for it to pay (autoGpuParticles), else
/// Cpu, and falls back to the CPU (saying why) when CUDA fails.
enum class Device { Cpu, Cuda, Auto };
const char* deviceName(Device d);               ///< "cpu", "cuda", "auto"
Device deviceFromName(const std::string& name); ///< ValueError for unknown names

/// Device::Auto's rule (README, "Which device"): a frame of particles goes to the GPU when the
/// run's particles, the frame's times Context::framesInRun(), reach this many for `threads` host
/// threads: 1M x (threads / 4)^1.45, about 7.5M at 16. Measured on an H200 host (whole processes,
/// the default pipeline, generated drops): one frame ran faster on its CPU below 1M particles at 4
/// threads, 2-3M at 8 and 7-8M at 16, where the GPU's fixed costs (its context, 0.2-0.3 s a
/// process, and the copies) outweigh what it saves; ten frames with one context, below
/// 2.5M particles in all at 16 threads.
double autoGpuParticles(int threads);

/// The run was cancelled by the progress callback (or Ctrl-C in the CLI).
class Cancelled : public Error
{
public:
    explicit Cancelled(const std::string& msg = "cancelled") : Error(msg) {}
};

/// Nested wall-clock timings: scopes open inside each other on the calling thread.
class TimingTree
{
public:
    struct Node
    {
        std::string name;
        double seconds = 0;
        double peakMiB = 0; ///< the process's peak resident memory when the node ended
        std::vector<size_t> children;
        size_t parent = 0;
    };

    /// Measures from construction to destruction into a child of the innermost open scope.
    class Scope
    {
    public:
        Scope(TimingTree& tree, const std::string& name);
        ~Scope();
        Scope(const Scope&) = delete;
        Scope& operator=(const Scope&) = delete;

    private:
        TimingTree& mTree;
        size_t mNode;
        double mStart;
    };

    TimingTree();
    /// Forget every node and restart the root's clock.
    void clear();
    /// Add a node measured elsewhere (e.g. a GPU's own events) under the innermost open scope.
    void add(const std::string& name, double seconds);
    /// The root's time: from construction or clear() to now (or to the last finish()).
    void finish();

    const std::vector<Node>& nodes() const { return mNodes; } ///< nodes()[0] is the root
    const Node& root() const { return mNodes[0]; }
    /// The innermost open scope's name ("" outside every scope).
    const std::string& current() const { return mNodes[mOpen].name; }
    /// Seconds of the first node named name (0 when absent).
    double seconds(const std::string& name) const;
    bool has(const std::string& name) const;

    /// An indented tree: each node's seconds, share of the total and peak memory.
    std::string format() const;
    /// {"name": .., "seconds": .., "peak_mib": .., "children": [..]}
    std::string toJson() const;

private:
    std::vector<Node> mNodes;
    size_t mOpen = 0;
    double mStart = 0;
};

/// What the progress callback sees at each checkpoint.
struct ProgressEvent
{
    const std::string& stage; ///< the innermost timing scope, e.g. "field"
    size_t ranges;            ///< ranges that went on since the context was made or reset()
};

/// Return false to cancel. Called from worker threads, one call at a time.
using ProgressCallback = std::function<bool(const ProgressEvent&)>;

class Context
{
public:
    explicit Context(Device device = Device::Cpu) : mDevice(device) {}

    Device device() const { return mDevice; }
    void setDevice(Device d) { mDevice = d; }

    /// Device::Auto's hint: the frames this run converts, which share one CUDA context's making
    /// (autoGpuParticles). 1 unless a front end says more (the CLI: the frames it has to do).
    size_t framesInRun() const { return mFramesInRun; }
    void setFramesInRun(size_t n) { mFramesInRun = n > 0 ? n : 1; }

    /// At most this many worker threads while a stage runs (0: all cores). The CLI's -j.
    int threads() const { return mThreads; }
    /// ValueError outside [0, kMaxThreads]: TBB's arenas are not made for more (past 65536
    /// they crashed), and no machine has that many cores.
    void setThreads(int n);
    /// The threads a run on this context has: threads() where set, at most the cores this
    /// process may use; else those cores.
    int runThreads() const;
    static constexpr int kMaxThreads = 4096;

    /// The most memory one request may take, in bytes: stages estimate what a large structure
    /// will need before they build it and refuse past this (requireMemory), so an oversized
    /// request fails at once with the estimate instead of being killed by the kernel, or
    /// taking the machine down with it. 0 (the default): the process's (MemoryBudget.h).
    size_t memoryBudget() const;
    void setMemoryBudget(size_t bytes) { mMemoryBudget = bytes; }
    /// ValueError "WHAT needs about N MiB, more than the memory budget of M MiB ..." when
    /// bytes passes memoryBudget().
    void requireMemory(double bytes, const std::string& what) const;

    TimingTree& timing() { return mTiming; }
    const TimingTree& timing() const { return mTiming; }
    /// Shorthand for a timing scope: auto t = ctx.scope("field");
    TimingTree::Scope scope(const std::string& name) { return TimingTree::Scope(mTiming, name); }

    void setProgress(ProgressCallback callback) { mProgress = std::move(callback); }
    /// Ask for a stop from outside the callback (a signal handler's flag, another thread).
    void cancel() { mCancelled.store(true); }
    bool cancelled() const { return mCancelled.load(); }
    /// Called once per range by every parallel stage: reports progress, and throws Cancelled
    /// once a stop was asked for. Thread-safe.
    void checkpoint();
    /// Throws Cancelled when a stop was asked for (between stages, on the calling thread).
    void throwIfCancelled() const;
    /// Ranges that passed their checkpoint (and ran) while a progress callback was set, since the
    /// context was made or reset().
    size_t rangesBegun() const { return mRanges.load(); }
    /// Clear the cancel flag and the range count (the timing tree is cleared separately).
    void reset();

private:
    Device mDevice;
    int mThreads = 0;
    size_t mFramesInRun = 1;
    size_t mMemoryBudget = 0;
    TimingTree mTiming;
    ProgressCallback mProgress;
    std::mutex mProgressMutex;
    std::atomic<bool> mCancelled{false};
    std::atomic<size_t> mRanges{0};
};

/// The process's peak resident memory so far, MiB.
double peakMemoryMiB();

} // namespace fluidsurf
