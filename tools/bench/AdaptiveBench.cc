// AdaptiveBench.cc - `fluidsurf_bench adaptive`: the thesis' Tables 6.1-6.3 per scene - uniform
// grids of voxel 2r and r against the 3-level grid (its default, and curvature alone as in the
// thesis: --level-tolerance 0): time, triangles (per level, and the crack patches), peak memory,
// and the distance of each mesh to the uniform-r mesh; plus OpenVDB's adaptive volumeToMesh of the
// uniform-r level set with its adaptivity tuned to the adaptive mesh's triangle count.
#include "Bench.h"
#include "OpenVdbBaselines.h"

#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/Reconstruct.h>

#include <tbb/info.h>

#include <malloc.h>

#include <cmath>
#include <cstdio>

namespace fluidsurf {
namespace bench {

namespace {

struct Method
{
    const char* name;
    double voxel; ///< in r
    bool adaptive;
    double tolerance; ///< levelTolerance (adaptive)
    std::vector<double> seconds, peak;
    ReconstructResult last;
};

} // namespace

int runAdaptiveBench(const AdaptiveBenchOptions& o)
{
    std::printf("fluidsurf_bench adaptive: %d hardware threads; medians of %d runs, interleaved; "
                "raw meshes (no post-processing, isolated particles left out); memory: the "
                "process' peak above its resident size at the start of the run (freed memory "
                "trimmed first); distances to "
                "the uniform-r mesh, in r (Hausdorff: both ways, vertices and centroids; mean: "
                "from the mesh's points); curvature threshold %g\n\n",
                tbb::info::default_concurrency(), o.repeat, o.curvatureThreshold);
    std::printf("| scene | grid | s | x uniform r | triangles | x uniform r | level 2 / level 3 / "
                "patch | peak MiB | x uniform r | Hausdorff (r) | mean (r) | watertight |\n"
                "|---|---|---|---|---|---|---|---|---|---|---|---|\n");
    for (const Case& c : loadCases(o.scenes, o.shared)) {
        std::vector<Method> methods = {{"uniform r", 1, false, 0, {}, {}, {}},
                                       {"uniform 2r", 2, false, 0, {}, {}, {}},
                                       {"adaptive", 1, true, o.levelTolerance, {}, {}, {}},
                                       {"adaptive, curvature alone", 1, true, 0, {}, {}, {}}};
        for (int k = 0; k < o.repeat; ++k)
            for (Method& m : methods) {
                ReconstructParams p = ReconstructParams::fromRadius(c.radius);
                p.field.voxelSize = m.voxel;
                p.field.adaptive = m.adaptive;
                p.field.levelTolerance = m.tolerance;
                p.field.curvatureThreshold = o.curvatureThreshold;
                p.post.decimate = 0, p.post.smooth = 0, p.post.subdivide = 0;
                p.post.isolated = IsolatedMode::Drop;
                m.last = ReconstructResult(); // the previous run's result is not held
                malloc_trim(0);               // and its memory is given back first
                resetPeakRss();
                const double base = statusMiB("VmRSS"); // resident now
                Context ctx;
                m.seconds.push_back(seconds([&] { m.last = reconstruct(c.particles, p, ctx); }));
                m.peak.push_back(peakRssMiB() - base);
            }
        const Method& uniform = methods[0];
        const double t0 = median(uniform.seconds), p0 = median(uniform.peak);
        const size_t n0 = uniform.last.mesh.triangles.size();
        const double reach = 8 * c.radius;
        auto row = [&](const char* name, double s, double peak, const TriangleMesh& mesh,
                       const std::string& levels) {
            const MeshReport r = checkMesh(mesh);
            const double h = std::max(meshDistance(mesh, uniform.last.mesh, reach),
                                      meshDistance(uniform.last.mesh, mesh, reach));
            const double mean = meanMeshDistance(mesh, uniform.last.mesh, reach);
            char time[64] = "", mem[64] = "";
            if (s > 0)
                std::snprintf(time, sizeof(time), "%.3f | %.2f", s, s / t0);
            else
                std::snprintf(time, sizeof(time), "|");
            if (peak > 0)
                std::snprintf(mem, sizeof(mem), "%.0f | %.2f", peak, peak / p0);
            else
                std::snprintf(mem, sizeof(mem), "|");
            std::printf("| %s | %s | %s | %zu | %.3f | %s | %s | %.3f | %.3f | %s |\n",
                        c.name.c_str(), name, time, mesh.triangles.size(),
                        double(mesh.triangles.size()) / double(n0), levels.c_str(), mem,
                        h / c.radius, mean / c.radius,
                        r.watertight() ? "yes" : describe(r).c_str());
            std::fflush(stdout);
        };
        for (const Method& m : methods) {
            std::string levels;
            if (m.adaptive) {
                const AdaptiveMeshStats& a = m.last.adaptiveMesh;
                levels = std::to_string(a.level2Triangles) + " / " +
                         std::to_string(a.level3Triangles) + " / " +
                         std::to_string(a.patchTriangles);
            }
            row(m.name, median(m.seconds), median(m.peak), m.last.mesh, levels);
        }
        // OpenVDB's adaptive volumeToMesh of the uniform-r level set, its adaptivity bisected
        // (in log scale: the count falls steeply just above 0) to the adaptive mesh's triangle
        // count, within 2% or the closest of 16 steps; at adaptivity 0 it may have fewer already
        const size_t target = methods[2].last.mesh.triangles.size();
        double best = 0;
        TriangleMesh bestMesh = openvdbAdaptiveMesh(*uniform.last.levelSet, 0);
        auto off = [&](const TriangleMesh& m) {
            return std::abs(double(m.triangles.size()) - double(target));
        };
        if (bestMesh.triangles.size() > target) {
            double lo = std::log(1e-6), hi = 0;
            for (int step = 0; step < 16 && off(bestMesh) > 0.02 * double(target); ++step) {
                const double a = std::exp(0.5 * (lo + hi));
                TriangleMesh m = openvdbAdaptiveMesh(*uniform.last.levelSet, a);
                (m.triangles.size() > target ? lo : hi) = std::log(a);
                if (off(m) < off(bestMesh)) bestMesh = std::move(m), best = a;
            }
        }
        char name[96];
        std::snprintf(name, sizeof(name), "OpenVDB volumeToMesh of uniform r, adaptivity %.3g",
                      best);
        row(name, -1, -1, bestMesh, "");
    }
    return 0;
}

} // namespace bench
} // namespace fluidsurf
