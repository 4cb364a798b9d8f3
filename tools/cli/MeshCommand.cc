// MeshCommand.cc - `fluidsurf mesh IN.vdb -o OUT.obj` (level set -> mesh) and
// `fluidsurf reconstruct IN -o OUT.obj [--vdb OUT.vdb]` (particles -> mesh in one pass).
#include "Commands.h"
#include "FieldOptions.h"
#include "Frames.h"
#include "Progress.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/MeshLevelSet.h>
#include <fluidsurf/Rasterize.h>
#include <fluidsurf/io/MeshIO.h>
#include <fluidsurf/io/ParticleIO.h>

#include <chrono>
#include <cstdio>
#include <memory>

namespace fluidsurf {
namespace cli {

namespace {

using Clock = std::chrono::steady_clock;
double since(Clock::time_point t)
{
    return std::chrono::duration<double>(Clock::now() - t).count();
}

struct MeshOptions
{
    std::string input, output, frames, grid, mesher = "mc", vdb;
    FieldOptions field;
    int threads = 0;
    bool check = false, dropNonFinite = false, quiet = false, verbose = false;
};

void addMeshOutputOptions(CLI::App* cmd, MeshOptions& o)
{
    cmd->add_option("-o,--output", o.output, "output mesh (.obj, .ply or .vtk) or pattern")
        ->required();
    cmd->add_option("--frames", o.frames, "frame range A-B for a pattern");
    cmd->add_option("--mesher", o.mesher,
                    "mc (our marching cubes) or openvdb (OpenVDB's volumeToMesh)")
        ->capture_default_str()
        ->check(CLI::IsMember({"mc", "openvdb"}));
    cmd->add_option("-j,--threads", o.threads, "worker threads (default: all cores)")
        ->check(CLI::NonNegativeNumber);
    cmd->add_flag(
        "--check", o.check,
        "check the mesh (boundary and non-manifold edges, orientation, ...) and print it");
    cmd->add_flag("-q,--quiet", o.quiet, "no progress bar and no per-frame lines");
    cmd->add_flag("-v,--verbose", o.verbose, "per-stage timings and peak memory");
}

std::vector<FrameJob> planMeshJobs(const MeshOptions& o)
{
    auto jobs = planFrames(o.input, o.output, o.frames);
    for (const FrameJob& job : jobs)
        if (io::meshFormatFromPath(job.output) == io::MeshFormat::Unknown)
            throw ValueError("output '" + job.output + "' must end in .obj, .ply or .vtk");
    return jobs;
}

/// Mesh a grid, write it, and print the frame's line (and the stage lines with -v).
void meshAndWrite(const MeshOptions& o, const openvdb::FloatGrid& grid, const FrameJob& job,
                  bool bar, std::vector<StageTime>& stages)
{
    MeshStats ms;
    const TriangleMesh mesh = meshLevelSet(grid, mesherFromName(o.mesher), &ms);
    stages.push_back({std::string("mesh (") + o.mesher + ")", ms.seconds});
    const auto t = Clock::now();
    io::writeMesh(mesh, job.output);
    stages.push_back({"write mesh", since(t)});
    if (!o.quiet && !bar) {
        double total = 0;
        for (const StageTime& s : stages)
            total += s.seconds;
        std::printf("%s -> %s: %zu vertices, %zu triangles, %.3f s\n", job.input.c_str(),
                    job.output.c_str(), mesh.points.size(), mesh.triangles.size(), total);
    }
    if (o.verbose) {
        for (const StageTime& s : stages)
            std::printf("  %-16s %8.4f s\n", s.name.c_str(), s.seconds);
        std::printf("  peak memory %.1f MiB\n", peakRssMiB());
    }
    if (o.check) std::printf("  mesh: %s\n", describe(checkMesh(mesh)).c_str());
}

} // namespace

Runner addMeshCommand(CLI::App& app)
{
    auto o = std::make_shared<MeshOptions>();
    CLI::App* cmd = app.add_subcommand("mesh", "Level set(s) (.vdb) to triangle mesh(es)");
    cmd->add_option("input", o->input, ".vdb file or frame pattern")->required();
    cmd->add_option("--grid", o->grid,
                    "name of the float grid to mesh (default: the first level set)");
    addMeshOutputOptions(cmd, *o);
    cmd->footer(
        "Examples:\n"
        "  fluidsurf mesh frame.vdb -o frame.obj\n"
        "  fluidsurf mesh smoke.vdb --grid surface --mesher openvdb -o surface.ply\n"
        "  fluidsurf mesh 'vdb/f_{:04}.vdb' -o 'obj/f_{:04}.obj' --frames 1-100\n"
        "Reads any VDB level set (ours or another tool's); meshes its zero crossing with\n"
        "outward (counter-clockwise) triangles and vertex normals from the field gradient.");
    return [o]() {
        const auto jobs = planMeshJobs(*o);
        const auto threads = limitThreads(o->threads);
        Progress bar(jobs.size(), "mesh", o->quiet);
        for (size_t i = 0; i < jobs.size(); ++i) {
            bar.update(i, jobs[i].input);
            std::vector<StageTime> stages;
            const auto t = Clock::now();
            const openvdb::FloatGrid::Ptr grid = readLevelSet(jobs[i].input, o->grid);
            stages.push_back({"read", since(t)});
            meshAndWrite(*o, *grid, jobs[i], bar.enabled(), stages);
        }
        bar.finish();
        return 0;
    };
}

Runner addReconstructCommand(CLI::App& app)
{
    auto o = std::make_shared<MeshOptions>();
    CLI::App* cmd = app.add_subcommand(
        "reconstruct", "Particle frame(s) to triangle mesh(es), level set in memory");
    cmd->add_option("input", o->input, "particle file or frame pattern")->required();
    cmd->add_option("--vdb", o->vdb, "also write the level set to this .vdb file or pattern");
    addFieldOptions(cmd, o->field);
    addMeshOutputOptions(cmd, *o);
    cmd->add_flag("--drop-nonfinite", o->dropNonFinite,
                  "drop particles with NaN/Inf coordinates instead of failing");
    cmd->footer(
        "Examples:\n"
        "  fluidsurf reconstruct frame.bgeo -r 0.025 -o frame.obj\n"
        "  fluidsurf reconstruct frame.bgeo -r 0.025 -o frame.obj --vdb frame.vdb --check\n"
        "  fluidsurf reconstruct 'sim/f_{:04}.bgeo' -r 0.025 -o 'obj/f_{:04}.obj' --frames 1-100\n"
        "The same field as 'rasterize' (all its options), then marching cubes.");
    return [o]() {
        auto jobs = planMeshJobs(*o);
        std::vector<FrameJob> vdbJobs;
        if (!o->vdb.empty()) vdbJobs = planVdbFrames(o->input, o->vdb, o->frames, "--vdb");
        const auto threads = limitThreads(o->threads);
        io::ReadOptions ro;
        ro.dropNonFinite = o->dropNonFinite;
        prepareDevice(o->field);
        Progress bar(jobs.size(), "reconstruct", o->quiet);
        double radius = 0;
        for (size_t i = 0; i < jobs.size(); ++i) {
            bar.update(i, jobs[i].input);
            std::vector<StageTime> stages;
            auto t = Clock::now();
            io::ReadInfo ri;
            const ParticleSet ps = io::readParticles(jobs[i].input, ro, &ri);
            stages.push_back({"read", since(t)});
            if (i == 0) radius = chooseRadius(o->field, ps, !o->quiet); // one r for the sequence
            const RasterizeResult res =
                rasterizeParticles(ps, makeParams(o->field, radius), jobs[i].input);
            for (const StageTime& s : res.stats.stages)
                stages.push_back(s);
            if (!vdbJobs.empty()) {
                t = Clock::now();
                writeLevelSet({res.grid}, vdbJobs[i].output);
                stages.push_back({"write vdb", since(t)});
            }
            if (!o->quiet && !bar.enabled() && (res.stats.isolated || ri.droppedNonFinite))
                std::printf("%s: %zu isolated particles %s, %zu non-finite dropped\n",
                            jobs[i].input.c_str(), res.stats.isolated,
                            o->field.keepIsolated ? "kept as spheres" : "left out",
                            ri.droppedNonFinite);
            meshAndWrite(*o, *res.grid, jobs[i], bar.enabled(), stages);
            if (o->verbose) printDevice(res.stats);
        }
        bar.finish();
        return 0;
    };
}

} // namespace cli
} // namespace fluidsurf
