// Options.h - the options `rasterize`, `mesh` and `reconstruct` share, bound straight to the
// library's ReconstructParams (lengths relative to r, as the library takes them), and what every
// command does around its library call: the context (device, threads, Ctrl-C), the radius line,
// the -v timing tree and the --stats JSON.
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/io/ParticleIO.h>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <memory>

#include <string>
#include <vector>

namespace fluidsurf {
namespace cli {

struct PipelineOptions
{
    ReconstructParams params; ///< params.field: lengths in r
    std::string field = "ssp07", method = "narrow-band", device = "cpu", mesher = "mc",
                isolated = "spheres", decimate = "0.8", decimator = "quadric", volume = "particles";
    bool ignoreRadiusAttribute = false;
    bool raw = false; ///< --raw: no decimation, smoothing or subdivision
    int threads = 0;
    std::string maxMemory; ///< --max-memory SIZE: the context's memory budget ("" the default)
    bool quiet = false, verbose = false, check = false;
    std::string stats; ///< --stats FILE.json

    /// The params after parsing (enum names, radius attribute, --decimate, --raw). ValueError for a
    /// --decimate that is neither a fraction nor "off".
    ReconstructParams resolved() const;
    /// A context for these options: device, threads, and Ctrl-C as a clean stop. The returned
    /// object holds -j for the whole process while it lives (file writing included).
    std::unique_ptr<tbb::global_control> setUp(Context& ctx) const;
    /// setUp's device, threads and Ctrl-C for another context (a frame's, in a sequence).
    void configure(Context& ctx) const;
};

void addFieldOptions(CLI::App* cmd, PipelineOptions& o);
/// Bytes from "8G", "500M", "64K" or a plain number of bytes (binary units); ValueError
/// naming --max-memory otherwise, or for less than 1 MiB.
size_t parseMemorySize(const std::string& text);
/// -j, -q, -v, --stats (every pipeline command); --check and --mesher as the command makes.
/// What a command makes: a level set (no mesh options), a mesh from a level set (--check and
/// --mesher), or a mesh from a mesh (--check).
enum class Makes { LevelSet, MeshedLevelSet, Mesh };
void addRunOptions(CLI::App* cmd, PipelineOptions& o, Makes makes);

/// --attributes NAME,...: particle attributes carried onto the output; where says where to.
void addAttributesOption(CLI::App* cmd, PipelineOptions& o, const char* where);

/// r for a sequence from its first frame, printed with its source (an estimate as "ESTIMATE");
/// the estimate is timed in ctx.
double chooseSequenceRadius(const PipelineOptions& o, const ParticleSet& first, Context& ctx);

/// The start of every particle frame: a fresh timing tree, the timed read, a stop check, and on
/// the first frame the sequence's radius into params.radius (one r for the whole sequence:
/// surfaces of neighbouring frames must match).
ParticleSet readFrame(const PipelineOptions& o, Context& ctx, const std::string& path,
                      const io::ReadOptions& read, io::ReadInfo& info, bool first,
                      ReconstructParams& params);

/// On stderr: a non-empty frame gave no surface (no active voxel or no triangle); names the
/// likely cause (r against the spacing estimate, or every particle isolated).
void warnIfEmpty(const std::string& input, const ParticleSet& ps, const RasterizeStats& s,
                 double radius, bool noTriangles);

/// The per-frame report: -v prints the timing tree (and, after a rasterization, where the field
/// ran); --stats collects every frame and is written at the end.
class Report
{
public:
    explicit Report(const PipelineOptions& o) : mOptions(o) {}
    /// Call after ctx.timing().finish() for each frame; counts are name -> value.
    void frame(const std::string& input, const Context& ctx,
               const std::vector<std::pair<std::string, double>>& counts,
               const RasterizeStats* field = nullptr);
    /// Writes --stats (atomically) when given.
    void finish() const;

private:
    const PipelineOptions& mOptions;
    std::vector<std::string> mFrames; ///< JSON objects
};

/// Counts for the report.
std::vector<std::pair<std::string, double>> fieldCounts(const RasterizeStats& s);
std::vector<std::pair<std::string, double>> meshCounts(const MeshReport& r);

/// Runs one frame's work so that every error names the frame's file, whatever layer raised it
/// (the pipeline's limits, OpenVDB's exceptions, std::bad_alloc); messages that name it already
/// pass unchanged. A stop (Cancelled) passes through.
template <typename F> auto forFile(const std::string& file, F&& work) -> decltype(work())
{
    try {
        return work();
    } catch (const Cancelled&) {
        throw;
    } catch (const Error& e) {
        if (std::string(e.what()).find(file) != std::string::npos) throw;
        throw Error(file + ": " + e.what());
    } catch (const openvdb::Exception& e) {
        throw Error(file + ": " + e.what());
    } catch (const std::bad_alloc&) {
        throw Error(file + ": out of memory");
    }
}

/// Ctrl-C (SIGINT) or SIGTERM asks every context set up by PipelineOptions to stop; a second
/// signal ends the process at once.
void installInterruptHandler();
bool interrupted();
/// 130 after SIGINT, 143 after SIGTERM (the shell's 128 + signal).
int interruptExitCode();
/// Between stages and frames: Cancelled when ctx was stopped or Ctrl-C came.
void stopIfInterrupted(const Context& ctx);

} // namespace cli
} // namespace fluidsurf
