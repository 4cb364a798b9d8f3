// Bench.h - benchmark cases of fluidsurf_bench and the timing helpers they share.
#pragma once

#include <fluidsurf/PostProcess.h>

#include <fluidsurf/Params.h>
#include <fluidsurf/ParticleSet.h>
#include <fluidsurf/Scenes.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <string>
#include <vector>

namespace fluidsurf {
namespace bench {

struct ReadBenchOptions
{
    size_t count = 2000000;
    int repeat = 7;
    std::string dir = "/tmp";
    std::string shared = "../shared/data";
    bool json = false;
};

int runReadBench(const ReadBenchOptions& options);

struct FieldBenchOptions
{
    std::string scenes = "real,drop-1M,block-1M";
    std::string voxels = "1";   ///< in r
    std::string supports = "4"; ///< R in r
    std::string methods = "narrow-band,narrow-band-1,gather-full,scatter,p2ls,smooth";
    int repeat = 3;
    std::string shared = "../shared/data";
};

int runFieldBench(const FieldBenchOptions& options);

struct MeshBenchOptions
{
    std::string scenes = "real,drop-1M,block-1M";
    std::string voxels = "1"; ///< in r (R = 4r)
    int repeat = 3;
    std::string shared = "../shared/data";
    std::string dir = "/tmp"; ///< where the whole-pipeline rows write their OBJ
};

int runMeshBench(const MeshBenchOptions& options);

struct PostBenchOptions
{
    std::string scenes = "real,large,drop-1M";
    double decimate = 0.8;                   ///< the share of triangles removed
    double decimateError = 0;                ///< and the error bound, in voxels (0: none)
    int smooth = PostProcessParams().smooth; ///< rounds of smoothing
    int repeat = 3;
    int openMeshRepeat = 1; ///< runs of OpenMesh's serial Decimater (0: none)
    std::string shared = "../shared/data";
};

int runPostBench(const PostBenchOptions& options);

struct AdaptiveBenchOptions
{
    std::string scenes = "large,drop-1M";
    double curvatureThreshold = Params().curvatureThreshold;
    double levelTolerance = Params().levelTolerance; ///< of the "adaptive" rows
    int repeat = 3;
    std::string shared = "../shared/data";
};

int runAdaptiveBench(const AdaptiveBenchOptions& options);

struct SequenceBenchOptions
{
    int frames = 20;
    size_t count = 1000000; ///< particles per frame (about)
    double radius = 0.01;   ///< r of the generated frames
    std::string format = "xyz";
    std::string inFlight = "1,2,3,4"; ///< the one-process ways: --in-flight values
    std::string args;                 ///< more reconstruct options, e.g. "--device cuda"
    std::string fluidsurf;            ///< the CLI; empty: the one beside fluidsurf_bench
    int repeat = 3;
    std::string dir = "/tmp"; ///< where the frames and meshes go (removed at the end)
};

int runSequenceBench(const SequenceBenchOptions& options);

struct QualityBenchOptions
{
    std::string jitters = "0.2,0.3,0.4";               ///< of the slab, in lattice spacings
    size_t count = 20000;                              ///< slab particles
    double radius = 0.025;                             ///< slab r
    int layers = 6;                                    ///< slab thickness in particles
    std::string scenes = "real,large";                 ///< the volume rows
    std::string field = "ssp07";                       ///< our rows' field (Params::field)
    int smooth = PostProcessParams().smooth;           ///< our default rows' rounds of smoothing
    bool flatten = PostProcessParams().flatten;        ///< our default rows' flattening
    bool cover = PostProcessParams().cover;            ///< our default rows' covering
    uint64_t seed = SceneParams().seed;                ///< the slab's jitter
    double radiusScale = Params().radiusScale;         ///< our rows' Params::radiusScale
    double anisotropyRatio = Params().anisotropyRatio; ///< our rows' Params::anisotropyRatio
    std::string volume = volumeTargetName(PostProcessParams().volume); ///< our default rows'
    std::string splashsurf;   ///< splashsurf 0.14's program for same-run rows; empty: none
    std::string dir = "/tmp"; ///< where splashsurf's input and output go (removed after)
    std::string shared = "../shared/data";
};

int runQualityBench(const QualityBenchOptions& options);

/// A whole process's wall time (spawn to exit) and peak RSS.
struct ProcessRun
{
    double seconds = 0, peakMiB = 0;
};

/// Runs argv to its end; Error when it cannot start or does not exit 0.
ProcessRun runProcess(const std::vector<std::string>& argv);

/// A benchmark scene: a real frame (with its file, for whole-process rows) or a generated one.
struct Case
{
    std::string name;
    ParticleSet particles;
    double radius;
    std::string path; ///< empty for generated scenes
};

/// "real" (the small real frames), "hilbert", or generated "drop-1M", "block-4M", ...
std::vector<Case> loadCases(const std::string& scenes, const std::string& shared);
std::vector<std::string> split(const std::string& commaSeparated);
void resetPeakRss(); ///< restart VmHWM (/proc/self/clear_refs)

inline double median(std::vector<double> v)
{
    std::sort(v.begin(), v.end());
    return v.empty()
               ? 0
               : (v.size() % 2 ? v[v.size() / 2] : 0.5 * (v[v.size() / 2 - 1] + v[v.size() / 2]));
}

template <typename F> double seconds(F&& f)
{
    const auto t0 = std::chrono::steady_clock::now();
    f();
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
}

/// A memory line of /proc/self/status ("VmHWM", "VmRSS"), in MiB.
inline double statusMiB(const std::string& field)
{
    FILE* f = std::fopen("/proc/self/status", "r");
    if (!f) return 0;
    const std::string format = field + ": %lf kB";
    char line[256];
    double kb = 0;
    while (std::fgets(line, sizeof(line), f))
        if (std::sscanf(line, format.c_str(), &kb) == 1) break;
    std::fclose(f);
    return kb / 1024.0;
}

/// Peak resident set size of this process so far, in MiB (VmHWM).
inline double peakRssMiB()
{
    return statusMiB("VmHWM");
}

} // namespace bench
} // namespace fluidsurf
