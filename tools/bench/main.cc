// main.cc - fluidsurf_bench: the benchmark program. Prints per-case wall-time medians,
// throughput and peak RSS as a Markdown table (or JSON with --json) for BENCHMARKS.md.
//   fluidsurf_bench io [--count N] [--repeat K]   particle read throughput per format
//   fluidsurf_bench field [--scenes ...]          rasterize stages vs baselines and OpenVDB
//   fluidsurf_bench mesh [--scenes ...]           meshing stage vs volumeToMesh; whole pipeline
//   fluidsurf_bench post [--scenes ...]           decimation, smoothing, subdivision (Table 5.1)
//   fluidsurf_bench adaptive [--scenes ...]       the 3-level grid vs uniform r, 2r
//   (Tables 6.1-6.3)
//   fluidsurf_bench sequence [--frames 20]        frames/s: a process per frame vs one for all
#include "Bench.h"

#include <CLI/CLI.hpp>

#include <malloc.h>

namespace {

/// The options every per-scene benchmark takes: which scenes, runs per case, the data folder.
void addSceneOptions(CLI::App* cmd, std::string& scenes, int& repeat, std::string& shared)
{
    cmd->add_option("--scenes", scenes,
                    "comma-separated: real, large, hilbert, drop-1M, block-1M, block-4M, ...")
        ->capture_default_str();
    cmd->add_option("--repeat", repeat, "runs per case (median)")->capture_default_str();
    cmd->add_option("--shared", shared, "../shared/data")->capture_default_str();
}

} // namespace

int main(int argc, char** argv)
{
    CLI::App app{"fluidsurf_bench - speed and memory of the fluidsurf stages"};
    app.require_subcommand(1);
    fluidsurf::bench::ReadBenchOptions io;
    CLI::App* ioCmd =
        app.add_subcommand("io", "particle read throughput per format on a generated frame");
    ioCmd->add_option("--count", io.count, "particles in the generated frame")
        ->capture_default_str();
    ioCmd->add_option("--repeat", io.repeat, "reads per format (median reported)")
        ->capture_default_str();
    ioCmd->add_option("--dir", io.dir, "folder for the temporary files")->capture_default_str();
    ioCmd
        ->add_option("--shared", io.shared,
                     "../shared/data to also time the real frames ('' to skip)")
        ->capture_default_str();
    ioCmd->add_flag("--json", io.json, "JSON instead of a Markdown table");
    fluidsurf::bench::FieldBenchOptions field;
    CLI::App* fieldCmd =
        app.add_subcommand("field", "rasterize per stage: narrow band vs baselines vs OpenVDB");
    addSceneOptions(fieldCmd, field.scenes, field.repeat, field.shared);
    fieldCmd->add_option("--voxel", field.voxels, "voxel sizes in r (comma-separated)")
        ->capture_default_str();
    fieldCmd->add_option("--support", field.supports, "influence radii R in r (comma-separated)")
        ->capture_default_str();
    fieldCmd
        ->add_option("--methods", field.methods,
                     "narrow-band, narrow-band-1 (one thread), narrow-band-cuda, "
                     "gather-full, scatter, p2ls, smooth; aniso, aniso-cuda (ssp07-aniso), yt10, "
                     "yt10-1, yt10-cuda: the field stage against narrow-band's (-1, -cuda), "
                     "listed before it")
        ->capture_default_str();
    fluidsurf::bench::MeshBenchOptions mesh;
    CLI::App* meshCmd = app.add_subcommand(
        "mesh", "meshing stage: our marching cubes vs volumeToMesh; whole pipeline");
    addSceneOptions(meshCmd, mesh.scenes, mesh.repeat, mesh.shared);
    meshCmd->add_option("--voxel", mesh.voxels, "voxel sizes in r (comma-separated)")
        ->capture_default_str();
    meshCmd->add_option("--dir", mesh.dir, "folder for the whole-pipeline OBJ")
        ->capture_default_str();
    fluidsurf::bench::PostBenchOptions post;
    CLI::App* postCmd = app.add_subcommand(
        "post", "decimation, smoothing and subdivision per scene (thesis Table 5.1) vs OpenMesh's "
                "Decimater");
    addSceneOptions(postCmd, post.scenes, post.repeat, post.shared);
    postCmd->add_option("--decimate", post.decimate, "share of the triangles removed")
        ->capture_default_str();
    postCmd->add_option("--decimate-error", post.decimateError, "error bound, voxels (0: none)")
        ->capture_default_str();
    postCmd->add_option("--smooth", post.smooth, "rounds of smoothing")->capture_default_str();
    postCmd
        ->add_option("--openmesh-repeat", post.openMeshRepeat,
                     "runs of OpenMesh's serial Decimater per case (0: skip it)")
        ->capture_default_str();
    fluidsurf::bench::AdaptiveBenchOptions adaptive;
    CLI::App* adaptiveCmd = app.add_subcommand(
        "adaptive", "the 3-level grid against uniform grids of voxel r and 2r and OpenVDB's "
                    "adaptive volumeToMesh (thesis Tables 6.1-6.3)");
    addSceneOptions(adaptiveCmd, adaptive.scenes, adaptive.repeat, adaptive.shared);
    adaptiveCmd->add_option("--curvature-threshold", adaptive.curvatureThreshold)
        ->capture_default_str();
    adaptiveCmd
        ->add_option("--level-tolerance", adaptive.levelTolerance,
                     "of the 'adaptive' rows, in voxels")
        ->capture_default_str();
    fluidsurf::bench::SequenceBenchOptions sequence;
    CLI::App* sequenceCmd = app.add_subcommand(
        "sequence", "frames per second of a sequence: one process per frame against one process "
                    "for all, with frames in flight");
    sequenceCmd->add_option("--frames", sequence.frames, "frames in the sequence")
        ->capture_default_str()
        ->check(CLI::Range(1, 9999));
    sequenceCmd->add_option("--count", sequence.count, "particles per frame (about)")
        ->capture_default_str();
    sequenceCmd->add_option("-r,--radius", sequence.radius, "particle radius of the frames")
        ->capture_default_str();
    sequenceCmd->add_option("--format", sequence.format, "frame file format (extension)")
        ->capture_default_str();
    sequenceCmd
        ->add_option("--in-flight", sequence.inFlight,
                     "the one-process ways: --in-flight values (comma-separated)")
        ->capture_default_str();
    sequenceCmd->add_option("--args", sequence.args,
                            "more reconstruct options for every way, e.g. \"--device cuda\"");
    sequenceCmd->add_option("--fluidsurf", sequence.fluidsurf,
                            "the fluidsurf program (default: the one beside this one)");
    sequenceCmd->add_option("--repeat", sequence.repeat, "rounds (median)")->capture_default_str();
    sequenceCmd->add_option("--dir", sequence.dir, "folder for the frames and meshes")
        ->capture_default_str();
    fluidsurf::bench::QualityBenchOptions quality;
    CLI::App* qualityCmd = app.add_subcommand(
        "quality", "flatness of a jittered slab's top face and enclosed volume of real frames: "
                   "ours raw and default, splashsurf 0.14 in the same run (--splashsurf)");
    qualityCmd->add_option("--jitters", quality.jitters, "slab jitters J (comma-separated)")
        ->capture_default_str();
    qualityCmd->add_option("--count", quality.count, "slab particles")->capture_default_str();
    qualityCmd->add_option("-r,--radius", quality.radius, "slab r")->capture_default_str();
    qualityCmd->add_option("--layers", quality.layers, "slab thickness")->capture_default_str();
    qualityCmd->add_option("--scenes", quality.scenes, "frames of the volume rows")
        ->capture_default_str();
    qualityCmd
        ->add_option("--field", quality.field, "our rows' field: ssp07, zb05, ssp07-aniso, yt10")
        ->capture_default_str();
    qualityCmd->add_option("--smooth", quality.smooth, "our default rows' rounds of smoothing")
        ->capture_default_str();
    qualityCmd->add_option("--flatten", quality.flatten, "our default rows' flattening: on or off")
        ->default_str("on");
    qualityCmd
        ->add_option("--cover", quality.cover,
                     "our default rows' covering of the centres left outside: on or off")
        ->default_str("on");
    qualityCmd->add_option("--seed", quality.seed, "the slab's jitter seed")->capture_default_str();
    qualityCmd->add_option("--radius-scale", quality.radiusScale, "our rows' radius scale")
        ->capture_default_str();
    qualityCmd->add_option("--aniso-ratio", quality.anisotropyRatio, "our rows' anisotropy ratio")
        ->capture_default_str();
    qualityCmd
        ->add_option("--volume", quality.volume,
                     "our default rows' volume target: mesh or particles")
        ->capture_default_str()
        ->check(CLI::IsMember({"mesh", "particles"}));

    qualityCmd->add_option("--splashsurf", quality.splashsurf,
                           "splashsurf's program, e.g. "
                           "/tmp/peers-new/splashsurf-0.14.0/target/release/splashsurf");
    qualityCmd->add_option("--dir", quality.dir, "folder for splashsurf's files")
        ->capture_default_str();
    qualityCmd->add_option("--shared", quality.shared, "../shared/data")->capture_default_str();
    bool coldAllocator = false;
    app.add_flag(
        "--cold-allocator", coldAllocator,
        "keep glibc's default malloc thresholds (big buffers come fresh from mmap each read)");
    CLI11_PARSE(app, argc, argv);
    if (!coldAllocator) {
        // glibc mmaps large buffers afresh until its adaptive threshold has grown, so the first
        // cases of a run would pay page faults the later ones do not. Fixed thresholds measure
        // every case the same way: parsing and copying with reused memory.
        mallopt(M_MMAP_THRESHOLD, 1 << 30);
        mallopt(M_TRIM_THRESHOLD, 1 << 30);
    }
    try {
        if (app.got_subcommand("io")) return fluidsurf::bench::runReadBench(io);
        if (app.got_subcommand("field")) return fluidsurf::bench::runFieldBench(field);
        if (app.got_subcommand("mesh")) return fluidsurf::bench::runMeshBench(mesh);
        if (app.got_subcommand("post")) return fluidsurf::bench::runPostBench(post);
        if (app.got_subcommand("adaptive")) return fluidsurf::bench::runAdaptiveBench(adaptive);
        if (app.got_subcommand("sequence")) return fluidsurf::bench::runSequenceBench(sequence);
        if (app.got_subcommand("quality")) return fluidsurf::bench::runQualityBench(quality);
    } catch (const std::exception& e) {
        std::fprintf(stderr, "fluidsurf_bench: error: %s\n", e.what());
        return 1;
    }
    return 0;
}
