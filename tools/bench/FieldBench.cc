// FieldBench.cc - `fluidsurf_bench field`: the rasterize pipeline per stage, against the thesis'
// baselines (gather-full, scatter), one thread, and OpenVDB's rasterizers, on the real frames
// and generated 1M/4M scenes. One Markdown row per case (median of --repeat runs).
#include "Bench.h"
#include "OpenVdbBaselines.h"

#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Scenes.h>
#include <fluidsurf/io/ParticleIO.h>

#include <tbb/global_control.h>

#include <fstream>
#include <map>
#include <sstream>

namespace fluidsurf {
namespace bench {

void resetPeakRss()
{
    std::ofstream f("/proc/self/clear_refs");
    f << "5";
}

std::vector<std::string> split(const std::string& s)
{
    std::vector<std::string> out;
    std::stringstream ss(s);
    for (std::string item; std::getline(ss, item, ',');)
        if (!item.empty()) out.push_back(item);
    return out;
}

std::vector<Case> loadCases(const std::string& scenes, const std::string& shared)
{
    std::vector<Case> cases;
    for (const std::string& name : split(scenes)) {
        if (name == "real") {
            const char* files[] = {"double_dam_break_frame_26_4732_particles.vtk",
                                   "dam_break_frame_9_6859_particles.bgeo",
                                   "dam_break_frame_23_24389_particles.bgeo",
                                   "hilbert_46843_particles.bgeo",
                                   "bunny_frame_14_7705_particles.vtk",
                                   "cube_2366_particles.vtk"};
            for (const char* f : files) {
                const std::string path = shared + "/real/" + f;
                std::ifstream probe(path);
                if (!probe) continue;
                cases.push_back({std::string(f).substr(0, std::string(f).find("_particles")),
                                 io::readParticles(path), 0.025, path});
            }
            continue;
        }
        if (name == "large") { // the DualSPHysics frames, r as ../shared/data/README.md gives it
            const std::pair<const char*, double> files[] = {
                {"dam_obstacle_t0.20_1704086_particles.xyz", 0.0018},
                {"dam_obstacle_t0.50_1694136_particles.xyz", 0.0018},
                {"dam_obstacle_t0.50_398850_particles.vtk", 0.0029}};
            for (const auto& [f, r] : files) {
                const std::string path = shared + "/large/" + f;
                if (!std::ifstream(path)) continue;
                cases.push_back({std::string(f).substr(0, std::string(f).find("_particles")),
                                 io::readParticles(path), r, path});
            }
            continue;
        }
        if (name.rfind("hilbert", 0) == 0) {
            const std::string path = shared + "/real/hilbert_46843_particles.bgeo";
            cases.push_back({"hilbert_46843", io::readParticles(path), 0.025, path});
            continue;
        }
        // drop-1M, block-4M, ...: generated, r = 0.025
        const size_t dash = name.find('-');
        if (dash == std::string::npos) throw std::runtime_error("unknown scene '" + name + "'");
        SceneParams sp;
        sp.count = size_t(std::stod(name.substr(dash + 1)) * (name.back() == 'M'   ? 1e6
                                                              : name.back() == 'k' ? 1e3
                                                                                   : 1));
        cases.push_back({name, generateScene(sceneFromName(name.substr(0, dash)), sp), sp.radius});
    }
    return cases;
}

namespace {
struct Row
{
    std::string scene, method;
    size_t particles = 0;
    double voxel = 0, support = 0;
    int threads = 0;
    double median = 0, peak = 0, evalRate = 0;
    size_t evaluations = 0, activeVoxels = 0;
    std::map<std::string, double> stages;
    std::string gpu; ///< with CUDA: the GPU's own timings (median of the runs), for a note line
    double gpuFieldMs = 0; ///< with the device pipeline: its sort through gather (CUDA events)
    /// The field computation, sort through gather: the CPU stages that the device pipeline
    /// replaces.
    double cpuFieldSeconds() const
    {
        double t = 0;
        for (const char* name : {"neighbors", "classify", "narrow band", "field"}) {
            auto it = stages.find(name);
            if (it != stages.end()) t += it->second;
        }
        return t;
    }
};

/// The device pipeline's stages from the sort through the gather (not upload, bounds, download).
bool isDeviceFieldStage(const std::string& name)
{
    return name == "sort" || name == "cells" || name == "classify" || name == "band" ||
           name == "isolated" || name == "gather";
}

Row runOurs(const Case& c, const Params& p, Device device, int threads, int repeat,
            const std::string& label)
{
    Row row{c.name, label, c.particles.size(), p.voxelSize / c.radius, p.influenceRadius / c.radius,
            threads};
    std::vector<double> totals;
    std::map<std::string, std::vector<double>> stages;
    Context ctx(device);
    ctx.setThreads(threads);
    resetPeakRss();
    std::map<std::string, std::vector<double>> gpu;
    std::vector<std::string> gpuOrder;
    size_t gpuBytes = 0;
    std::string ranOn;
    for (int k = 0; k < repeat; ++k) {
        ctx.timing().clear();
        const RasterizeResult r = rasterizeParticles(c.particles, p, ctx);
        // The stages are the children of the "rasterize" scope of the timing tree.
        const TimingTree& tree = ctx.timing();
        for (const TimingTree::Node& n : tree.nodes())
            if (n.name == "rasterize") {
                totals.push_back(n.seconds);
                for (size_t child : n.children)
                    stages[tree.nodes()[child].name].push_back(tree.nodes()[child].seconds);
            }
        for (const StageTime& s : r.stats.gpuStages) {
            if (!gpu.count(s.name)) gpuOrder.push_back(s.name);
            gpu[s.name].push_back(s.seconds);
        }
        gpuBytes = r.stats.gpuBytes, ranOn = r.stats.device;
        row.evaluations = r.stats.fieldEvaluations;
        row.activeVoxels = r.stats.activeVoxels;
    }
    if (!gpu.empty()) {
        std::string note = c.name + " on " + ranOn + ":";
        for (const std::string& name : gpuOrder) {
            char buf[96];
            std::snprintf(buf, sizeof(buf), " %s %.2f ms,", name.c_str(), median(gpu[name]) * 1e3);
            note += buf;
            if (isDeviceFieldStage(name)) row.gpuFieldMs += median(gpu[name]) * 1e3;
        }
        char buf[64];
        std::snprintf(buf, sizeof(buf), " peak %.1f MiB", double(gpuBytes) / (1 << 20));
        row.gpu = note + buf;
    }
    row.peak = peakRssMiB();
    row.median = median(totals);
    for (auto& [name, v] : stages)
        row.stages[name] = median(v);
    row.evalRate = row.evaluations / row.median * 1e-6;
    return row;
}

double stageOf(const Row& r, const char* name)
{
    const auto it = r.stages.find(name);
    return it == r.stages.end() ? 0 : it->second;
}

void printRow(const Row& r, double reference)
{
    std::string stages;
    for (const char* s :
         {"neighbors", "classify", "narrow band", "bounding volume", "kernel shapes", "field",
          "cuda context", "upload", "device field", "vdb build", "complete band", "level set"}) {
        auto it = r.stages.find(s);
        if (it == r.stages.end()) continue;
        char buf[64];
        std::snprintf(buf, sizeof(buf), "%s%.3f", stages.empty() ? "" : " / ", it->second);
        stages += buf;
    }
    std::printf(
        "| %s | %zu | %g r | %g r | %s | %d | %.3f | %s | %zu | %.1f | %zu | %.0f | %.2fx |\n",
        r.scene.c_str(), r.particles, r.voxel, r.support, r.method.c_str(), r.threads, r.median,
        stages.c_str(), r.evaluations, r.evalRate, r.activeVoxels, r.peak,
        reference > 0 ? r.median / reference : 1.0);
    std::fflush(stdout);
}
} // namespace

int runFieldBench(const FieldBenchOptions& o)
{
    const int hw = int(tbb::info::default_concurrency());
    std::printf(
        "fluidsurf_bench field: %d hardware threads; seconds are medians of %d runs; stages: "
        "%s\n\n",
        hw, o.repeat,
        "CPU: neighbors / classify / narrow band (or bounding volume) / field / complete band / "
        "level set; "
        "CUDA: cuda context / upload / device field / vdb build / complete band / level set");
    std::printf("| scene | particles | voxel | R | method | threads | field stage s | stages s | "
                "evaluations | M evals/s "
                "| active voxels | peak RSS MiB | time / narrow band "
                "|\n|---|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    const std::vector<std::string> methods = split(o.methods);
    std::vector<std::string> gpuNotes, anisoNotes;
    for (const Case& c : loadCases(o.scenes, o.shared))
        for (const std::string& v : split(o.voxels))
            for (const std::string& s : split(o.supports)) {
                Params p = Params::fromRadius(c.radius);
                p.voxelSize = std::stod(v) * c.radius;
                p.influenceRadius = std::stod(s) * c.radius;
                double reference = 0, cpuField = 0, cpuField1 = 0;
                double ssp07Field = 0, ssp07Field1 = 0, ssp07DeviceField = 0; // field stages, s
                for (const std::string& m : methods) {
                    if (m == "narrow-band-cuda") {
                        p.method = FieldMethod::NarrowBand;
                        const Row r =
                            runOurs(c, p, Device::Cuda, hw, o.repeat, "narrow band, CUDA");
                        printRow(r, reference);
                        ssp07DeviceField = stageOf(r, "device field");
                        std::string note = r.gpu;
                        if (r.gpuFieldMs > 0) {
                            char buf[200];
                            std::snprintf(buf, sizeof(buf),
                                          "; field computation (sort to gather) %.2f ms",
                                          r.gpuFieldMs);
                            note += buf;
                            if (cpuField > 0) {
                                std::snprintf(buf, sizeof(buf),
                                              " = %.1fx faster than %d threads (%.1f ms)",
                                              cpuField * 1e3 / r.gpuFieldMs, hw, cpuField * 1e3);
                                note += buf;
                            }
                            if (cpuField1 > 0) {
                                std::snprintf(buf, sizeof(buf),
                                              ", %.0fx faster than 1 thread (%.0f ms)",
                                              cpuField1 * 1e3 / r.gpuFieldMs, cpuField1 * 1e3);
                                note += buf;
                            }
                        }
                        gpuNotes.push_back(note);
                    } else if (m == "narrow-band" || m == "narrow-band-1") {
                        p.method = FieldMethod::NarrowBand;
                        const Row r = runOurs(c, p, Device::Cpu, m == "narrow-band" ? hw : 1,
                                              o.repeat, "narrow band");
                        if (m == "narrow-band")
                            reference = r.median, cpuField = r.cpuFieldSeconds(),
                            ssp07Field = stageOf(r, "field");
                        else
                            cpuField1 = r.cpuFieldSeconds(), ssp07Field1 = stageOf(r, "field");
                        printRow(r, reference);
                    } else if (m == "aniso" || m == "aniso-cuda" || m == "yt10" || m == "yt10-1" ||
                               m == "yt10-cuda") {
                        // ssp07-aniso and yt10 (issue 64; yt10 as the thesis' Table 4.11: one
                        // thread, all, the GPU): the field stage against SSP07's in this run
                        Params a = p;
                        a.method = FieldMethod::NarrowBand;
                        a.field = m.rfind("yt10", 0) == 0 ? FieldKind::Yt10 : FieldKind::Ssp07Aniso;
                        const bool cuda = m.find("cuda") != std::string::npos;
                        const int threads = m == "yt10-1" ? 1 : hw;
                        const std::string label =
                            std::string(fieldName(a.field)) + (cuda           ? ", CUDA"
                                                               : threads == 1 ? ", 1 thread"
                                                                              : "");
                        const Row r = runOurs(c, a, cuda ? Device::Cuda : Device::Cpu, threads,
                                              o.repeat, label);
                        printRow(r, reference);
                        const double base = cuda           ? ssp07DeviceField
                                            : threads == 1 ? ssp07Field1
                                                           : ssp07Field;
                        char ratio[32] = "(run narrow-band first)";
                        if (base > 0)
                            std::snprintf(ratio, sizeof(ratio), "%.2fx",
                                          stageOf(r, "field") / base);
                        char buf[320];
                        std::snprintf(buf, sizeof(buf),
                                      "%s, %s: kernel shapes %.1f ms, field %.1f ms, complete "
                                      "band %.1f ms; field / SSP07's %s %s",
                                      c.name.c_str(), r.method.c_str(),
                                      stageOf(r, "kernel shapes") * 1e3, stageOf(r, "field") * 1e3,
                                      stageOf(r, "complete band") * 1e3,
                                      cuda           ? "device field"
                                      : threads == 1 ? "field (1 thread)"
                                                     : "field",
                                      ratio);
                        anisoNotes.push_back(buf);
                        if (cuda && !r.gpu.empty()) gpuNotes.push_back(r.gpu);
                    } else if (m == "gather-full" || m == "scatter") {
                        p.method = methodFromName(m);
                        printRow(runOurs(c, p, Device::Cpu, m == "scatter" ? 1 : hw,
                                         std::max(1, o.repeat / 2), m),
                                 reference);
                    } else if (m == "p2ls" || m == "smooth") {
                        std::vector<double> t, setup;
                        BaselineResult b;
                        resetPeakRss();
                        for (int k = 0; k < std::max(1, o.repeat / 2); ++k) {
                            b = m == "p2ls"
                                    ? runParticlesToLevelSet(c.particles, c.radius, p.voxelSize)
                                    : runSmoothSpheres(c.particles, c.radius, p.influenceRadius,
                                                       p.voxelSize);
                            t.push_back(b.seconds), setup.push_back(b.setupSeconds);
                        }
                        Row r{c.name,
                              m == "p2ls" ? "OpenVDB ParticlesToLevelSet"
                                          : "OpenVDB rasterizeSmoothSpheres",
                              c.particles.size(),
                              p.voxelSize / c.radius,
                              p.influenceRadius / c.radius,
                              hw};
                        r.median = median(t);
                        if (m == "smooth")
                            r.stages["neighbors"] = median(setup); // PointDataGrid build
                        r.activeVoxels = b.activeVoxels;
                        r.peak = peakRssMiB();
                        printRow(r, reference);
                    } else {
                        throw std::runtime_error("unknown method '" + m + "'");
                    }
                }
            }
    if (!anisoNotes.empty()) {
        std::printf("\nssp07-aniso and yt10 (medians; the field stage against SSP07's in the same "
                    "run, CUDA against the device pipeline's whole field, sort to gather):\n\n");
        for (const std::string& n : anisoNotes)
            std::printf("- %s\n", n.c_str());
    }
    if (!gpuNotes.empty()) {
        std::printf("\nGPU timings (CUDA events, medians of the runs; the field computation is "
                    "sort through gather,\n"
                    "compared with the CPU's neighbors + classify + narrow band + field in the "
                    "same run):\n\n");
        for (const std::string& n : gpuNotes)
            std::printf("- %s\n", n.c_str());
    }
    return 0;
}

} // namespace bench
} // namespace fluidsurf
