// Kwargs.cc - keyword parameters -> Settings: one table, read both ways (set and default).
#include "Kwargs.h"

#include <fluidsurf/Error.h>

#include <algorithm>
#include <atomic>
#include <mutex>

#include <signal.h>

#include <cmath>
#include <functional>
#include <pythread.h>
#include <vector>

namespace py = pybind11;

namespace fluidsurf {
namespace python {

namespace {

struct Entry
{
    const char* name;
    unsigned group;
    std::function<void(Settings&, py::handle)> set;
    std::function<py::object(const Settings&)> get;
};

std::string typeOf(py::handle v)
{
    return py::str(py::type::handle_of(v).attr("__name__"));
}

double real(const char* name, py::handle v)
{
    // bool is an int in Python; a flag given as a number is a mistake worth reporting
    if (py::isinstance<py::bool_>(v) ||
        !(py::isinstance<py::float_>(v) || py::isinstance<py::int_>(v)))
        throw py::type_error(std::string(name) + " must be a number (got " + typeOf(v) + ")");
    return v.cast<double>();
}

double positive(const char* name, py::handle v)
{
    const double x = real(name, v);
    if (!std::isfinite(x) || !(x > 0))
        throw ValueError(std::string(name) + " must be a positive finite number (got " +
                         std::string(py::str(v)) + ")");
    return x;
}

double nonNegative(const char* name, py::handle v)
{
    const double x = real(name, v);
    if (!std::isfinite(x) || x < 0)
        throw ValueError(std::string(name) + " must be a finite number >= 0 (got " +
                         std::string(py::str(v)) + ")");
    return x;
}

int integer(const char* name, py::handle v, long lo, long hi)
{
    if (py::isinstance<py::bool_>(v) || !py::isinstance<py::int_>(v))
        throw py::type_error(std::string(name) + " must be an int (got " + typeOf(v) + ")");
    const long x = v.cast<long>();
    if (x < lo || x > hi)
        throw ValueError(std::string(name) + " must be in [" + std::to_string(lo) + ", " +
                         std::to_string(hi) + "] (got " + std::to_string(x) + ")");
    return int(x);
}

bool flag(const char* name, py::handle v)
{
    if (!py::isinstance<py::bool_>(v))
        throw py::type_error(std::string(name) + " must be True or False (got " + typeOf(v) + ")");
    return v.cast<bool>();
}

std::string text(const char* name, py::handle v)
{
    if (!py::isinstance<py::str>(v))
        throw py::type_error(std::string(name) + " must be a str (got " + typeOf(v) + ")");
    return v.cast<std::string>();
}

// Field lengths are stored in r (ReconstructParams::field), as the CLI takes them; half_width in
// voxels.
#define FS_POSITIVE(NAME, MEMBER)                                                                  \
    Entry                                                                                          \
    {                                                                                              \
        NAME, kField,                                                                              \
            [](Settings& s, py::handle v) { s.params.field.MEMBER = positive(NAME, v); },          \
            [](const Settings& s) -> py::object { return py::float_(s.params.field.MEMBER); }      \
    }
#define FS_REAL(NAME, GROUP, MEMBER, CHECK)                                                        \
    Entry                                                                                          \
    {                                                                                              \
        NAME, GROUP, [](Settings& s, py::handle v) { s.params.MEMBER = CHECK(NAME, v); },          \
            [](const Settings& s) -> py::object { return py::float_(s.params.MEMBER); }            \
    }
#define FS_INT(NAME, GROUP, MEMBER, LO, HI)                                                        \
    Entry                                                                                          \
    {                                                                                              \
        NAME, GROUP,                                                                               \
            [](Settings& s, py::handle v) { s.params.MEMBER = integer(NAME, v, LO, HI); },         \
            [](const Settings& s) -> py::object { return py::int_(s.params.MEMBER); }              \
    }
#define FS_CHOICE(NAME, GROUP, MEMBER, FROM, TO)                                                   \
    Entry                                                                                          \
    {                                                                                              \
        NAME, GROUP, [](Settings& s, py::handle v) { s.params.MEMBER = FROM(text(NAME, v)); },     \
            [](const Settings& s) -> py::object { return py::str(TO(s.params.MEMBER)); }           \
    }

const std::vector<Entry>& table()
{
    static const std::vector<Entry> entries = {
        FS_POSITIVE("voxel", voxelSize),
        FS_POSITIVE("influence", influenceRadius),
        FS_POSITIVE("smoothing_length", smoothingLength),
        FS_POSITIVE("band", bandWidth),
        FS_POSITIVE("half_width", halfWidth),
        FS_REAL("t_low", kField, field.tLow, real),
        FS_REAL("t_high", kField, field.tHigh, real),
        FS_REAL("radius_scale", kField, field.radiusScale, real),
        FS_INT("surface_neighbours", kField, field.surfaceNeighbours, 0, 1000000),
        FS_INT("splash_neighbours", kField, field.splashNeighbours, 0, 1000000),
        FS_REAL("color_field", kField, field.colorFieldThreshold, nonNegative),
        FS_CHOICE("field", kField, field.field, fieldFromName, fieldName),
        FS_REAL("aniso_ratio", kField, field.anisotropyRatio, real),
        FS_POSITIVE("aniso_radius", anisotropyRadius),
        FS_INT("aniso_neighbours", kField, field.anisotropyNeighbours, 0, 10000),
        FS_REAL("centre_smoothing", kField, field.centreSmoothing, real),
        FS_REAL("iso_level", kField, field.isoLevel, real),
        FS_CHOICE("method", kField, field.method, methodFromName, methodName),
        Entry{"ignore_radius_attribute", kField,
              [](Settings& s, py::handle v) {
                  s.params.field.perParticleRadii = !flag("ignore_radius_attribute", v);
              },
              [](const Settings& s) -> py::object {
                  return py::bool_(!s.params.field.perParticleRadii);
              }},
        Entry{
            "keep_isolated", kField,
            [](Settings& s, py::handle v) {
                s.params.field.keepIsolated = flag("keep_isolated", v);
            },
            [](const Settings& s) -> py::object { return py::bool_(s.params.field.keepIsolated); }},
        Entry{"adaptive", kField,
              [](Settings& s, py::handle v) { s.params.field.adaptive = flag("adaptive", v); },
              [](const Settings& s) -> py::object { return py::bool_(s.params.field.adaptive); }},
        FS_REAL("curvature_threshold", kField, field.curvatureThreshold, nonNegative),
        FS_REAL("level_tolerance", kField, field.levelTolerance, nonNegative),
        FS_CHOICE("mesher", kMesh, mesh.mesher, mesherFromName, mesherName),
        Entry{"decimate", kPost,
              [](Settings& s, py::handle v) {
                  // the CLI's --decimate off
                  if (py::isinstance<py::str>(v) && v.cast<std::string>() == "off")
                      s.params.post.decimate = 0;
                  else
                      s.params.post.decimate = nonNegative("decimate", v);
              },
              [](const Settings& s) -> py::object { return py::float_(s.params.post.decimate); }},
        FS_REAL("decimate_error", kPost, post.decimateError, nonNegative),
        FS_CHOICE("decimator", kPost, post.decimator, decimatorFromName, decimatorName),
        FS_INT("smooth", kPost, post.smooth, 0, 100),
        Entry{"flatten", kPost,
              [](Settings& s, py::handle v) { s.params.post.flatten = flag("flatten", v); },
              [](const Settings& s) -> py::object { return py::bool_(s.params.post.flatten); }},
        FS_INT("subdivide", kPost, post.subdivide, 0, 3),
        Entry{"raw", kPost, [](Settings& s, py::handle v) { s.raw = flag("raw", v); },
              [](const Settings& s) -> py::object { return py::bool_(s.raw); }},
        FS_CHOICE("isolated", kSpheres, post.isolated, isolatedModeFromName, isolatedModeName),
        FS_CHOICE("volume", kSpheres, post.volume, volumeTargetFromName, volumeTargetName),
        FS_REAL("sphere_deviation", kSpheres, post.sphereDeviation, positive),
        Entry{"cover", kSpheres,
              [](Settings& s, py::handle v) { s.params.post.cover = flag("cover", v); },
              [](const Settings& s) -> py::object { return py::bool_(s.params.post.cover); }},
        Entry{"threads", kRun,
              [](Settings& s, py::handle v) {
                  s.threads = integer("threads", v, 0, Context::kMaxThreads);
              },
              [](const Settings& s) -> py::object { return py::int_(s.threads); }},
        Entry{"max_memory", kRun,
              [](Settings& s, py::handle v) { s.maxMemory = nonNegative("max_memory", v); },
              [](const Settings& s) -> py::object { return py::float_(s.maxMemory); }},
        Entry{"device", kRun,
              [](Settings& s, py::handle v) { s.device = deviceFromName(text("device", v)); },
              [](const Settings& s) -> py::object { return py::str(deviceName(s.device)); }},
    };
    return entries;
}

#undef FS_POSITIVE
#undef FS_REAL
#undef FS_INT
#undef FS_CHOICE

} // namespace

Settings settingsFrom(const py::kwargs& kwargs, unsigned groups)
{
    Settings s;
    for (auto item : kwargs) {
        const std::string name = py::str(item.first);
        const Entry* entry = nullptr;
        for (const Entry& e : table())
            if ((e.group & groups) && name == e.name) entry = &e;
        if (!entry)
            throw py::type_error("unknown parameter '" + name +
                                 "' (known: " + describeParams(groups) + ")");
        entry->set(s, item.second);
    }
    if (s.raw) {
        if (kwargs.contains("decimate") || kwargs.contains("decimate_error") ||
            kwargs.contains("smooth") || kwargs.contains("flatten") ||
            kwargs.contains("subdivide") || kwargs.contains("decimator") ||
            kwargs.contains("volume") || kwargs.contains("cover"))
            throw ValueError("raw=True excludes decimate, decimate_error, decimator, smooth, "
                             "flatten, subdivide, volume and cover");
        PostProcessParams& p = s.params.post;
        p.decimate = 0, p.decimateError = 0, p.smooth = 0, p.subdivide = 0;
    }
    if (s.params.post.decimate >= 1)
        throw ValueError("decimate must be a fraction in [0, 1) or 'off' (got " +
                         std::to_string(s.params.post.decimate) + ")");
    return s;
}

void setUp(Context& ctx, const Settings& s)
{
    ctx.setDevice(s.device);
    ctx.setThreads(s.threads);
    ctx.setMemoryBudget(size_t(std::min(s.maxMemory, 1e18)));
}

namespace {
std::mutex gInterruptMutex;
int gInterruptScopes = 0; ///< live InterruptScopes (calls from the main thread only: nested ones)
struct sigaction gPythonHandler;
std::atomic<bool> gInterruptFired{false};

extern "C" void onPythonInterrupt(int signal, siginfo_t* info, void* context)
{
    gInterruptFired.store(true);
    // Python's own handler: it marks the signal for PyErr_CheckSignals
    if (gPythonHandler.sa_flags & SA_SIGINFO)
        gPythonHandler.sa_sigaction(signal, info, context);
    else if (gPythonHandler.sa_handler != SIG_DFL && gPythonHandler.sa_handler != SIG_IGN)
        gPythonHandler.sa_handler(signal);
}

bool inMainThread()
{
    static const unsigned long main =
        py::module_::import("threading").attr("main_thread")().attr("ident").cast<unsigned long>();
    return PyThread_get_thread_ident() == main;
}
} // namespace

InterruptScope::InterruptScope(Context& ctx)
{
    if (!inMainThread()) return;
    std::lock_guard<std::mutex> lock(gInterruptMutex);
    if (gInterruptScopes == 0) {
        struct sigaction now;
        if (::sigaction(SIGINT, nullptr, &now) != 0) return;
        const bool python =
            (now.sa_flags & SA_SIGINFO) || (now.sa_handler != SIG_DFL && now.sa_handler != SIG_IGN);
        if (!python) return; // ignored, or the default: not ours to change
        gPythonHandler = now;
        struct sigaction ours = now;
        ours.sa_flags = (now.sa_flags | SA_SIGINFO) & ~SA_RESETHAND;
        ours.sa_sigaction = onPythonInterrupt;
        gInterruptFired.store(false);
        if (::sigaction(SIGINT, &ours, nullptr) != 0) return;
    }
    ++gInterruptScopes;
    mInstalled = true;
    ctx.setProgress([](const ProgressEvent&) { return !gInterruptFired.load(); });
}

InterruptScope::~InterruptScope()
{
    if (!mInstalled) return;
    std::lock_guard<std::mutex> lock(gInterruptMutex);
    if (--gInterruptScopes == 0) ::sigaction(SIGINT, &gPythonHandler, nullptr);
}

bool InterruptScope::fired() const
{
    return mInstalled && gInterruptFired.load();
}

py::dict defaults(unsigned groups)
{
    const Settings s;
    py::dict d;
    for (const Entry& e : table())
        if (e.group & groups) d[e.name] = e.get(s);
    return d;
}

std::string describeParams(unsigned groups)
{
    std::string out;
    for (auto item : defaults(groups)) {
        if (!out.empty()) out += ", ";
        out += std::string(py::str(item.first)) + "=" + std::string(py::repr(item.second));
    }
    return out;
}

} // namespace python
} // namespace fluidsurf
