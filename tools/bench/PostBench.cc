// PostBench.cc - `fluidsurf_bench post`: the thesis' Table 5.1 (field + triangulation,
// decimation, smoothing (ours), subdivision, the whole chain in one call, total, triangle
// counts) per scene, with OpenMesh's serial Decimater reaching the same triangle count on the
// same raw mesh as the baseline row, and what each costs in fidelity: the symmetric Hausdorff
// distance to the raw mesh (voxels) and the enclosed volume against the raw mesh's.
#include "Bench.h"

#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/PostProcess.h>
#include <fluidsurf/Reconstruct.h>

#include <tbb/info.h>

#include <cmath>
#include <cstdio>

namespace fluidsurf {
namespace bench {

namespace {

struct Fidelity
{
    double hausdorffVoxels, volumeRatio;
    MeshReport report;
};

Fidelity fidelity(const TriangleMesh& raw, const MeshReport& rawReport, const TriangleMesh& mesh,
                  double voxel)
{
    Fidelity f{};
    f.report = checkMesh(mesh);
    // 4 voxels of reach: far past anything these steps should do (a miss reads "inf")
    f.hausdorffVoxels =
        std::max(meshDistance(mesh, raw, 4 * voxel), meshDistance(raw, mesh, 4 * voxel)) / voxel;
    f.volumeRatio = f.report.volume / rawReport.volume;
    return f;
}

} // namespace

int runPostBench(const PostBenchOptions& o)
{
    std::printf("fluidsurf_bench post: %d hardware threads; seconds are medians of %d runs (the "
                "OpenMesh row: of %d); voxel = r, R = 4r; decimation removes %.0f%%, error bound "
                "%g voxel; the one-call row's ratio is the median of its runs' ratios, each run "
                "timed right after a field + triangulation run\n\n",
                tbb::info::default_concurrency(), o.repeat, o.openMeshRepeat, 100 * o.decimate,
                o.decimateError);
    std::printf("| scene | step | s | triangles | x field+tri time | Hausdorff to raw (voxels) "
                "| volume / raw | thin (<10 deg) | watertight |\n"
                "|---|---|---|---|---|---|---|---|---|\n");
    for (const Case& c : loadCases(o.scenes, o.shared)) {
        // field + triangulation: reconstruct() with nothing after the mesher; each run followed
        // by the whole chain on its mesh, as reconstruct runs it (one call, components and
        // volumes once): their ratio is taken run by run, so that a slow spell of a shared
        // machine weighs on both sides of it
        ReconstructParams rp = ReconstructParams::fromRadius(c.radius);
        rp.post.decimate = 0, rp.post.smooth = 0, rp.post.subdivide = 0;
        rp.post.isolated = IsolatedMode::Drop;
        PostProcessParams all;
        all.decimate = o.decimate, all.decimateError = o.decimateError, all.smooth = o.smooth;
        ReconstructResult raw;
        TriangleMesh processed;
        std::vector<double> t, chain, ratio;
        for (int k = 0; k < o.repeat; ++k) {
            Context ctx;
            t.push_back(seconds([&] { raw = reconstruct(c.particles, rp, ctx); }));
            all.voxelSize = raw.levelSet->voxelSize()[0];
            chain.push_back(seconds([&] { processed = postProcessMesh(raw.mesh, all, ctx); }));
            ratio.push_back(chain.back() / t.back());
        }
        const double fieldTri = median(t);
        const double voxel = raw.levelSet->voxelSize()[0];
        const MeshReport rawReport = checkMesh(raw.mesh);
        // a step's row; its fidelity columns when it made a mesh of its own
        auto row = [&](const char* step, double s, const TriangleMesh& m, bool ownMesh,
                       double ratio = -1) {
            std::string tail = "| | | | |";
            if (ownMesh) {
                const Fidelity f = fidelity(raw.mesh, rawReport, m, voxel);
                char buf[256];
                std::snprintf(buf, sizeof(buf), "| %.3f | %.4f | %zu | %s |", f.hausdorffVoxels,
                              f.volumeRatio, f.report.thinTriangles,
                              f.report.watertight() ? "yes" : describe(f.report).c_str());
                tail = buf;
            }
            std::printf("| %s | %s | %.3f | %zu | %.2f %s\n", c.name.c_str(), step, s,
                        m.triangles.size(), ratio >= 0 ? ratio : s / fieldTri, tail.c_str());
            std::fflush(stdout);
        };
        std::printf("| %s | field + triangulation | %.3f | %zu | 1.00 | 0 | 1 | %zu | %s |\n",
                    c.name.c_str(), fieldTri, raw.mesh.triangles.size(), rawReport.thinTriangles,
                    rawReport.watertight() ? "yes" : describe(rawReport).c_str());

        // each step on the last one's mesh, alone (PostProcessParams with the others off)
        auto step = [&](const TriangleMesh& in, PostProcessParams p, TriangleMesh& out) {
            p.voxelSize = voxel;
            std::vector<double> times;
            for (int k = 0; k < o.repeat; ++k) {
                Context ctx;
                times.push_back(seconds([&] { out = postProcessMesh(in, p, ctx); }));
            }
            return median(times);
        };
        PostProcessParams dec;
        dec.decimate = o.decimate, dec.decimateError = o.decimateError;
        dec.smooth = 0, dec.subdivide = 0;
        TriangleMesh decimated, smoothed, subdivided;
        const double decSeconds = step(raw.mesh, dec, decimated);
        row("decimation (ours)", decSeconds, decimated, true);
        PostProcessParams sm;
        sm.decimate = 0, sm.smooth = o.smooth, sm.subdivide = 0;
        const double smSeconds = step(decimated, sm, smoothed);
        row("smoothing", smSeconds, smoothed, true);
        PostProcessParams sub;
        sub.decimate = 0, sub.smooth = 0, sub.subdivide = 1;
        const double subSeconds = step(smoothed, sub, subdivided);
        row("subdivision (1 Loop step)", subSeconds, subdivided, true);
        row("decimation + smoothing + subdivision (the rows above)",
            decSeconds + smSeconds + subSeconds, subdivided, false);
        // the chain, timed beside the reconstruction above (its ratio: the median run by run)
        const double post = median(chain);
        row("post-processing, one call (as reconstruct)", post, processed, true, median(ratio));
        row("total", fieldTri + post, processed, false);

        if (o.openMeshRepeat > 0) {
            // the same triangle count as ours reached (an error bound may have stopped it)
            PostProcessParams om = dec;
            om.decimator = Decimator::OpenMesh, om.decimateError = 0;
            om.decimate =
                1 - double(decimated.triangles.size()) / double(raw.mesh.triangles.size());
            TriangleMesh baseline;
            t.clear();
            for (int k = 0; k < o.openMeshRepeat; ++k) {
                Context ctx;
                t.push_back(seconds([&] { baseline = postProcessMesh(raw.mesh, om, ctx); }));
            }
            const double omSeconds = median(t);
            row("decimation (OpenMesh, serial)", omSeconds, baseline, true);
            std::printf("| %s | OpenMesh / ours, decimation | %.1fx | | | | | | |\n",
                        c.name.c_str(), omSeconds / decSeconds);
        }
    }
    return 0;
}

} // namespace bench
} // namespace fluidsurf
