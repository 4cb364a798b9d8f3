// MeshBench.cc - `fluidsurf_bench mesh`: the meshing stage (our marching cubes vs OpenVDB's
// volumeToMesh on the same grid, and ours on the GPU where there is one) against the field
// stage, and the whole pipeline per scene (read, field, mesh, write OBJ). One Markdown row per
// case (median of --repeat runs).
#include "Bench.h"

#include <fluidsurf/MeshLevelSet.h>
#include <fluidsurf/Rasterize.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/io/MeshIO.h>
#include <fluidsurf/io/ParticleIO.h>

#include <tbb/info.h>

#include <cstdio>

namespace fluidsurf {
namespace bench {

int runMeshBench(const MeshBenchOptions& o)
{
    const int hw = tbb::info::default_concurrency();
    std::printf(
        "fluidsurf_bench mesh: %d hardware threads; seconds are medians of %d runs; R = 4r\n\n", hw,
        o.repeat);
    std::printf(
        "| scene | particles | voxel | field stage s | mesher | mesh s | mesh / field | triangles "
        "| M triangles/s "
        "| peak RSS MiB | volumeToMesh / ours |\n|---|---|---|---|---|---|---|---|---|---|---|\n");
    std::vector<std::string> pipeline;
    for (const Case& c : loadCases(o.scenes, o.shared))
        for (const std::string& v : split(o.voxels)) {
            Params p = Params::fromRadius(c.radius);
            p.voxelSize = std::stod(v) * c.radius;
            std::vector<double> field;
            RasterizeResult res;
            for (int k = 0; k < o.repeat; ++k)
                field.push_back(seconds([&] { res = rasterizeParticles(c.particles, p); }));
            const double fieldSeconds = median(field);
            double ours = 0;
            for (Mesher m : {Mesher::MarchingCubes, Mesher::OpenVdb}) {
                std::vector<double> t;
                MeshStats ms;
                resetPeakRss();
                for (int k = 0; k < o.repeat; ++k)
                    t.push_back(seconds([&] { meshLevelSet(*res.grid, m, &ms); }));
                const double s = median(t);
                if (m == Mesher::MarchingCubes) ours = s;
                std::printf(
                    "| %s | %zu | %s r | %.3f | %s | %.4f | %.1f%% | %zu | %.1f | %.0f | %s |\n",
                    c.name.c_str(), c.particles.size(), v.c_str(), fieldSeconds,
                    m == Mesher::MarchingCubes ? "ours (mc)" : "OpenVDB volumeToMesh", s,
                    100 * s / fieldSeconds, ms.triangles, ms.triangles / s * 1e-6, peakRssMiB(),
                    m == Mesher::MarchingCubes
                        ? ""
                        : (std::to_string(s / ours).substr(0, 4) + "x").c_str());
                std::fflush(stdout);
            }
            // Our mesher on the GPU, where there is a usable one: an empty grid's mesh makes the
            // CUDA context (outside the timing) and says where it ran.
            Context gpu(Device::Auto);
            MeshStats gs;
            meshLevelSet(*openvdb::FloatGrid::create(), Mesher::MarchingCubes, gpu, &gs);
            if (gs.device.compare(0, 3, "cpu") != 0) {
                std::vector<double> t;
                resetPeakRss();
                for (int k = 0; k < o.repeat; ++k)
                    t.push_back(
                        seconds([&] { meshLevelSet(*res.grid, Mesher::MarchingCubes, gpu, &gs); }));
                const double s = median(t);
                std::printf("| %s | %zu | %s r | %.3f | ours (mc) on %s | %.4f | %.1f%% | %zu | "
                            "%.1f | %.0f | CPU mc / GPU: %.2fx |\n",
                            c.name.c_str(), c.particles.size(), v.c_str(), fieldSeconds,
                            gs.device.c_str(), s, 100 * s / fieldSeconds, gs.triangles,
                            gs.triangles / s * 1e-6, peakRssMiB(), ours / s);
                std::fflush(stdout);
            }
            // Whole pipeline, as `fluidsurf reconstruct` runs it (without process start-up):
            // read, the one library call reconstruct(), write.
            std::vector<double> read, total, write, wholeField, wholeMesh;
            const std::string out = o.dir + "/fluidsurf_bench_mesh.obj";
            ReconstructParams rp = ReconstructParams::fromRadius(c.radius);
            rp.field.voxelSize = std::stod(v);
            rp.keepGrids = false; // as the CLI without --vdb
            for (int k = 0; k < o.repeat; ++k) {
                double r = 0;
                ParticleSet loaded;
                if (!c.path.empty()) r = seconds([&] { loaded = io::readParticles(c.path); });
                Context ctx;
                ReconstructResult rr;
                const double call = seconds(
                    [&] { rr = reconstruct(c.path.empty() ? c.particles : loaded, rp, ctx); });
                const double w = seconds([&] { io::writeMesh(rr.mesh, out); });
                read.push_back(r), write.push_back(w), total.push_back(r + call + w);
                wholeField.push_back(ctx.timing().seconds("rasterize"));
                wholeMesh.push_back(ctx.timing().seconds("mesh"));
            }
            std::remove(out.c_str());
            char line[512];
            std::snprintf(
                line, sizeof(line), "| %s | %s r | %s | %.3f | %.3f | %.4f | %.3f | %.0f |",
                c.name.c_str(), v.c_str(),
                c.path.empty() ? "-" : std::to_string(median(read)).substr(0, 6).c_str(),
                median(wholeField), median(wholeMesh), median(write), median(total), peakRssMiB());
            pipeline.push_back(line);
        }
    std::printf(
        "\nWhole pipeline (read, field, our mesher, write OBJ with normals; no process "
        "start-up):\n\n"
        "| scene | voxel | read s | field s | mesh s | write OBJ s | total s | peak RSS MiB |\n"
        "|---|---|---|---|---|---|---|---|\n");
    for (const std::string& l : pipeline)
        std::printf("%s\n", l.c_str());
    return 0;
}

} // namespace bench
} // namespace fluidsurf
