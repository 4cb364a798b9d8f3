// Kwargs.h - the Python functions' keyword parameters: the CLI's long options with '-' written
// '_' (voxel, t_low, decimate_error, ...), the same values (lengths in r) and the same defaults,
// bound to the library's ReconstructParams. Unknown names are a TypeError listing the known ones,
// bad values a ValueError saying what is allowed.
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/Reconstruct.h>

#include <pybind11/pybind11.h>
#include <tbb/task_arena.h>

#include <string>

namespace fluidsurf {
namespace python {

/// Which call takes a parameter.
enum ParamGroup : unsigned {
    kField = 1,   ///< rasterize, reconstruct
    kMesh = 2,    ///< LevelSet.mesh, reconstruct
    kPost = 4,    ///< post_process, reconstruct
    kSpheres = 8, ///< reconstruct only, what needs the particles: spheres, the volume target
    kRun = 16,    ///< every computing call: threads, device
    kAll = kField | kMesh | kPost | kSpheres | kRun
};

/// What a call runs with: the parameters, and where and on how many threads.
struct Settings
{
    ReconstructParams params; ///< params.field: lengths in r, as the CLI's
    Device device = Device::Cpu;
    int threads = 0;      ///< 0: all cores
    double maxMemory = 0; ///< bytes, the context's memory budget; 0: its default
    bool raw = false;
};

/// Settings from a call's keyword arguments (only those of the groups given).
Settings settingsFrom(const pybind11::kwargs& kwargs, unsigned groups);

/// ctx for s (device, threads, memory budget).
void setUp(Context& ctx, const Settings& s);

/// While it lives, in the main thread, Ctrl-C (SIGINT) cancels ctx as well as doing what
/// Python's handler does: without it, the KeyboardInterrupt came only when a long call ended
/// (13 s late). Elsewhere (another thread, or SIGINT ignored or not Python's) it does nothing.
class InterruptScope
{
public:
    explicit InterruptScope(Context& ctx);
    ~InterruptScope();
    InterruptScope(const InterruptScope&) = delete;
    InterruptScope& operator=(const InterruptScope&) = delete;
    /// Whether a SIGINT came while it lived.
    bool fired() const;

private:
    bool mInstalled = false;
};

/// f without the GIL (other Python threads go on), inside a TBB arena of s.threads workers when
/// that is set, cancelled by Ctrl-C: the library stops within a range of work and the call
/// raises KeyboardInterrupt.
template <typename F> auto compute(const Settings& s, Context& ctx, F&& f) -> decltype(f())
{
    InterruptScope interrupt(ctx);
    try {
        pybind11::gil_scoped_release noGil;
        if (s.threads <= 0) return f();
        tbb::task_arena arena(s.threads);
        return arena.execute(f);
    } catch (const Cancelled&) {
        if (interrupt.fired() && PyErr_CheckSignals() != 0) throw pybind11::error_already_set();
        throw;
    }
}

/// {name: default} of the parameters of the groups given, as the CLI shows them.
pybind11::dict defaults(unsigned groups);

/// "name=default, ..." for docstrings.
std::string describeParams(unsigned groups);

} // namespace python
} // namespace fluidsurf
