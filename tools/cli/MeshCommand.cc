// MeshCommand.cc - `fluidsurf mesh IN.vdb -o OUT.obj` (level set -> mesh: meshLevelSet),
// `fluidsurf reconstruct IN -o OUT.obj [--vdb OUT.vdb]` (particles -> mesh: reconstruct) and
// `fluidsurf post IN.obj -o OUT.obj` (mesh -> mesh: postProcessMesh).
// Parse -> params -> one library call -> write -> report.
#include "Commands.h"
#include "Frames.h"
#include "Options.h"
#include "ProcessMemory.h"

#include "ParticleFrames.h"
#include "Progress.h"
#include "Sequence.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/TransferAttributes.h>
#include <fluidsurf/io/AtomicFile.h>
#include <fluidsurf/io/LevelSetIO.h>
#include <fluidsurf/io/MeshIO.h>
#include <fluidsurf/io/ParticleIO.h>

#include <cstdio>
#include <functional>
#include <memory>

namespace fluidsurf {
namespace cli {

namespace {

struct MeshOptions
{
    std::string input, output, frames, grid, vdb;
    PipelineOptions pipeline;
    SequenceOptions sequence;
    bool dropNonFinite = false;
    size_t inFlight = 0; ///< --in-flight (0: by the threads)
};

void addMeshOutputOptions(CLI::App* cmd, MeshOptions& o, Makes makes = Makes::MeshedLevelSet)
{
    cmd->add_option("-o,--output", o.output, "output mesh (.obj, .ply or .vtk) or pattern")
        ->required();
    cmd->add_option("--frames", o.frames, "frame range A-B for a pattern");
    addRunOptions(cmd, o.pipeline, makes);
    addSequenceOptions(cmd, o.sequence);
    addInFlightOption(cmd, o.inFlight);
}

std::vector<FrameJob> planMeshJobs(const MeshOptions& o)
{
    auto jobs = planFrames(o.input, o.output, o.frames);
    for (const FrameJob& job : jobs)
        if (io::meshFormatFromPath(job.output) == io::MeshFormat::Unknown)
            throw ValueError("output '" + job.output + "' must end in .obj, .ply or .vtk");
    return jobs;
}

/// Write the mesh beside what the group holds already, move them all into place, check the
/// mesh with --check, and print the frame's lines.
void writeAndReport(const MeshOptions& o, Context& ctx, const TriangleMesh& mesh,
                    const FrameJob& job, bool bar, Report& report, io::OutputGroup& outputs,
                    std::vector<std::pair<std::string, double>> counts,
                    const RasterizeStats* field = nullptr,
                    const std::vector<Attribute>& attributes = {})
{
    const PipelineOptions& po = o.pipeline;
    {
        const auto t = ctx.scope("write mesh");
        io::writeMesh(mesh, outputs.add(job.output), attributes);
        stopIfInterrupted(ctx); // a stop here keeps the frame's old files, all of them
        outputs.commit();
    }
    MeshReport check;
    if (po.check) {
        const auto t = ctx.scope("check");
        check = checkMesh(mesh);
    }
    ctx.timing().finish();
    if (!po.quiet && !bar)
        std::printf("%s -> %s: %zu vertices, %zu triangles, %.3f s\n", job.input.c_str(),
                    job.output.c_str(), mesh.points.size(), mesh.triangles.size(),
                    frameSeconds(ctx));
    if (po.check) {
        const auto more = meshCounts(check);
        counts.insert(counts.end(), more.begin(), more.end());
    } else {
        counts.push_back({"vertices", double(mesh.points.size())});
        counts.push_back({"triangles", double(mesh.triangles.size())});
    }
    report.frame(job.input, ctx, counts, field);
    if (po.check) std::printf("  mesh: %s\n", describe(check).c_str());
}

/// What mesh and post read of a frame: a level set file or a mesh, and a warning for its line.
struct MeshInput
{
    io::LevelSetFile levelSet;
    TriangleMesh mesh;
    std::string warning; ///< printed on stderr before the frame's lines
};
using Counts = std::vector<std::pair<std::string, double>>;
struct MeshFrame : FrameInFlight
{
    MeshInput input;
    TriangleMesh mesh;
    Counts counts;
};
/// A frame's input read from its file (timed as "read"); its mesh made from that input.
using ReadInput = std::function<void(const std::string& input, Context& ctx, MeshInput& in)>;
using MakeMesh =
    std::function<TriangleMesh(const std::string& input, MeshInput& in, Context& ctx, Counts&)>;

/// The frame loop of a command that turns each input file into one mesh (mesh, post): plan,
/// refuse to overwrite an input, then the frames in flight (FramesInFlight.h): read, make,
/// write and report, with a progress bar.
int runMeshFrames(const MeshOptions& o, const char* name, const ReadInput& read,
                  const MakeMesh& make)
{
    const PipelineOptions& po = o.pipeline;
    const auto jobs = planMeshJobs(o);
    checkRunFiles(inputsOf(jobs), outputsOf(jobs), po.stats);
    useHugePagesFor(inputBytes(jobs, shardOf(jobs, o.sequence.shard)), po.threads, interrupted);
    Context ctx;
    const auto threadLimit = po.setUp(ctx);
    prepareDevice(ctx.device()); // the CUDA context (0.1-0.3 s) made while the first file is read
    const std::vector<size_t> picked = shardOf(jobs, o.sequence.shard);
    SequenceRun run(o.sequence, po.quiet);
    const std::vector<size_t> todo =
        run.unfinished(picked, [&](size_t i) { return std::vector<std::string>{jobs[i].output}; });
    Progress bar(picked.size(), name, po.quiet);
    Report report(po);
    FrameRun fr{po, jobs, todo, o.inFlight, run, bar};
    FrameSteps<MeshFrame> steps;
    steps.read = [&](MeshFrame& f) {
        const auto t = f.ctx.scope("read");
        read(jobs[f.job].input, f.ctx, f.input);
    };
    steps.make = [&](MeshFrame& f) {
        stopIfInterrupted(f.ctx);
        f.mesh = make(jobs[f.job].input, f.input, f.ctx, f.counts);
        f.input.levelSet = io::LevelSetFile(), f.input.mesh = TriangleMesh();
    };
    steps.write = [&](MeshFrame& f) {
        if (!f.input.warning.empty()) std::fprintf(stderr, "%s", f.input.warning.c_str());
        io::OutputGroup outputs;
        writeAndReport(o, f.ctx, f.mesh, jobs[f.job], bar.enabled(), report, outputs, f.counts);
        stopIfInterrupted(f.ctx);
    };
    steps.clear = [](MeshFrame& f) {
        f.input = MeshInput(), f.mesh = TriangleMesh(), f.counts.clear();
    };
    runFramesInFlight(fr, steps);
    bar.finish();
    report.finish();
    return run.finish(name, picked.size());
}

/// --stats counts of post-processing: the triangles it took and left after decimation.
void addPostCounts(const PostProcessStats& s, std::vector<std::pair<std::string, double>>& counts)
{
    counts.push_back({"raw_triangles", double(s.inputTriangles)});
    counts.push_back({"decimated_triangles", double(s.decimatedTriangles)});
    counts.push_back({"decimate_error_voxels", s.decimateError});
    counts.push_back({"covered_particles", double(s.coveredParticles)});
    counts.push_back({"uncovered_particles", double(s.uncoveredParticles)});
}

/// --stats and -v counts of the adaptive mesher: triangles per level, crack patches and merged
/// crack points (cells per
/// level too where no field counts give them).
void addAdaptiveCounts(const AdaptiveMeshStats& s,
                       std::vector<std::pair<std::string, double>>& counts, bool cells)
{
    if (cells) {
        counts.push_back({"level2_cells", double(s.level2Cells)});
        counts.push_back({"level3_cells", double(s.level3Cells)});
    }
    counts.push_back({"level2_triangles", double(s.level2Triangles)});
    counts.push_back({"level3_triangles", double(s.level3Triangles)});
    counts.push_back({"patch_triangles", double(s.patchTriangles)});
    counts.push_back({"merged_crack_points", double(s.mergedCrackPoints)});
    counts.push_back({"open_cracks", double(s.openCracks)});
}

/// Decimation, smoothing and subdivision, for the commands that post-process a mesh.
void addPostOptions(CLI::App* cmd, PipelineOptions& o)
{
    PostProcessParams& p = o.params.post;
    std::vector<CLI::Option*> steps;
    steps.push_back(cmd->add_option("--decimate", o.decimate,
                                    "share of the triangles to remove by quadric error, cheapest "
                                    "first (flat bumps go first, as in the thesis); or off")
                        ->capture_default_str());
    steps.push_back(cmd->add_option("--decimate-error", p.decimateError,
                                    "also stop decimating where a vertex could end up more than "
                                    "K voxels from the input surface; 0 for no bound")
                        ->capture_default_str()
                        ->check(CLI::Range(0.0, 1e6)));
    steps.push_back(cmd->add_option("--decimator", o.decimator,
                                    "quadric (ours: parallel, the same result for any -j) or "
                                    "openmesh (OpenMesh's serial Decimater, the reference)")
                        ->capture_default_str()
                        ->check(CLI::IsMember({"quadric", "openmesh"})));
    steps.push_back(cmd->add_option("--smooth", p.smooth,
                                    "rounds of smoothing after decimation (along the normals, "
                                    "no point moving more than 0.2 voxel): takes out the "
                                    "particles' bumps on flat fluid; 0 to 100, 0 for none")
                        ->capture_default_str()
                        ->check(CLI::Range(0, 100)));
    steps.push_back(cmd->add_option("--flatten", p.flatten,
                                    "on or off: the smoothing then flattens flat fluid (plain "
                                    "Laplacian steps where the surface is flat over several "
                                    "voxels, none where it curves; no point moving more than "
                                    "0.4 voxel, volumes kept); needs --smooth above 0")
                        ->default_str("on")
                        ->check(CLI::IsMember({"on", "off"})));
    steps.push_back(cmd->add_option("--subdivide", p.subdivide,
                                    "Loop subdivision steps last (each 4x the triangles; rounds "
                                    "off the edges decimation leaves); 0 to 3")
                        ->capture_default_str()
                        ->check(CLI::Range(0, 3)));
    CLI::Option* raw = cmd->add_flag("--raw", o.raw,
                                     "no decimation, smoothing or subdivision: the mesh as "
                                     "marching cubes made it (or as read, for post)");
    for (CLI::Option* step : steps)
        raw->excludes(step);
}

/// Why a grid meshed to nothing, for the warning: a fog volume, an empty grid and a negative
/// background gave 0 triangles and no word (issue 63).
std::string whyNoSurface(const openvdb::FloatGrid& grid)
{
    if (grid.getGridClass() == openvdb::GRID_FOG_VOLUME)
        return "it is a fog volume (densities, 0 outside), not a level set; mesh a level set "
               "of it";
    if (grid.activeVoxelCount() == 0) return "it has no active voxels";
    if (grid.background() < 0)
        return "its background is negative, so that the outside reads as inside (a level "
               "set's is +half-width)";
    return "no value changes sign between active voxels (all inside or all outside)";
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
    cmd->add_option("--device", o->pipeline.device,
                    "cpu, cuda (marching cubes on the GPU, the same mesh byte for byte; the "
                    "openvdb mesher and adaptive files run on the CPU) or auto (cuda when a "
                    "usable GPU is present)")
        ->capture_default_str()
        ->check(CLI::IsMember({"cpu", "cuda", "auto"}));
    cmd->footer(
        "Examples:\n"
        "  fluidsurf mesh frame.vdb -o frame.obj\n"
        "  fluidsurf mesh frame.vdb -o frame.ply --device cuda\n"
        "  fluidsurf mesh smoke.vdb --grid surface --mesher openvdb -o surface.ply\n"
        "  fluidsurf mesh 'vdb/f_{:04}.vdb' -o 'obj/f_{:04}.obj' --frames 1-100\n"
        "Reads any VDB level set (ours or another tool's); meshes its zero crossing with\n"
        "outward (counter-clockwise) triangles and vertex normals from the field gradient.\n"
        "A file from 'reconstruct --adaptive --vdb' (grids surface, surface_fine, levels) is\n"
        "meshed adaptively, as reconstruct meshes it (--grid NAME meshes one grid alone).");
    return [o]() {
        const Mesher mesher = mesherFromName(o->pipeline.mesher);
        return runMeshFrames(
            *o, "mesh",
            [&](const std::string& input, Context&, MeshInput& in) {
                in.levelSet = io::readLevelSetFile(input, o->grid);
            },
            [&](const std::string& input, MeshInput& in, Context& ctx, Counts& counts) {
                if (!in.levelSet.adaptive.empty()) {
                    AdaptiveMeshStats as;
                    TriangleMesh mesh = meshAdaptiveGrid(in.levelSet.adaptive, ctx, &as);
                    addAdaptiveCounts(as, counts, true);
                    return mesh;
                }
                MeshStats ms;
                TriangleMesh mesh = meshLevelSet(*in.levelSet.grid, mesher, ctx, &ms);
                counts.push_back({"surface_cells", double(ms.surfaceCells)});
                if (mesh.empty())
                    in.warning = "fluidsurf: warning: " + input + ": no surface in grid '" +
                                 in.levelSet.grid->getName() +
                                 "': " + whyNoSurface(*in.levelSet.grid) + "\n";
                return mesh;
            });
    };
}

/// What became of a frame's isolated particles, for its line.
std::string isolatedFate(const ReconstructParams& params, const ReconstructResult& res)
{
    if (params.field.keepIsolated) return "kept in the field as spheres";
    if (params.post.isolated == IsolatedMode::Drop) return "left out";
    std::string s = "meshed as spheres";
    if (res.isolatedSpheres < res.isolatedParticles.size())
        s += " (" + std::to_string(res.isolatedParticles.size() - res.isolatedSpheres) +
             " too far from the origin for float32, left out)";
    return s;
}

Runner addPostCommand(CLI::App& app)
{
    auto o = std::make_shared<MeshOptions>();
    CLI::App* cmd = app.add_subcommand(
        "post", "Post-process triangle mesh(es): quadric decimation, smoothing, Loop subdivision");
    cmd->add_option("input", o->input, "mesh file (.obj or .ply) or frame pattern")->required();
    addMeshOutputOptions(cmd, *o, Makes::Mesh);
    addPostOptions(cmd, o->pipeline);
    cmd->add_option("--voxel-size", o->pipeline.params.post.voxelSize,
                    "the voxel that --decimate-error and the steps' bounds count in, world "
                    "units (default: the input's mean edge length; give the grid's voxel to "
                    "match reconstruct)")
        ->check(CLI::PositiveNumber);
    cmd->footer("Examples:\n"
                "  fluidsurf post frame.obj -o frame_smooth.obj\n"
                "  fluidsurf post frame.ply -o frame_light.ply --decimate 0.9 --subdivide 0\n"
                "  fluidsurf post frame.ply -o frame_fine.ply --decimate off --smooth 10\n"
                "  fluidsurf post 'obj/f_{:04}.obj' -o 'smooth/f_{:04}.ply' --frames 1-100\n"
                "Reads any triangle mesh (.obj, .ply) as the readers of particle files do: a\n"
                "broken file is one error and no output. Borders and non-manifold edges are\n"
                "kept as creases; a closed, oriented mesh stays so.");
    return [o]() {
        const PostProcessParams post = o->pipeline.resolved().post;
        return runMeshFrames(
            *o, "post",
            [&](const std::string& input, Context&, MeshInput& in) {
                std::vector<std::string> dropped;
                in.mesh = io::readMesh(input, &dropped);
                if (in.mesh.triangles.empty())
                    throw InputError(input + ": no triangles to post-process (" +
                                     std::to_string(in.mesh.points.size()) +
                                     " vertices: a point cloud, or a file cut short?)");
                if (dropped.empty()) return;
                std::string names;
                for (const std::string& n : dropped)
                    names += (names.empty() ? "" : " ") + n;
                in.warning = "fluidsurf: warning: " + input + ": vertex properties " + names +
                             " are not carried through post (reconstruct --attributes "
                             "evaluates them at the final vertices)\n";
            },
            [&](const std::string&, MeshInput& in, Context& ctx, Counts& counts) {
                const auto t = ctx.scope("post");
                PostProcessStats ps;
                TriangleMesh mesh = postProcessMesh(std::move(in.mesh), post, ctx, &ps);
                addPostCounts(ps, counts);
                return mesh;
            });
    };
}

Runner addReconstructCommand(CLI::App& app)
{
    auto o = std::make_shared<MeshOptions>();
    CLI::App* cmd = app.add_subcommand(
        "reconstruct", "Particle frame(s) to triangle mesh(es), level set in memory");
    cmd->add_option("input", o->input, "particle file or frame pattern")->required();
    cmd->add_option("--vdb", o->vdb, "also write the level set to this .vdb file or pattern");
    addFieldOptions(cmd, o->pipeline);
    addMeshOutputOptions(cmd, *o);
    cmd->add_flag("--drop-nonfinite", o->dropNonFinite,
                  "drop particles with NaN/Inf coordinates (or past 1e15) instead of failing");
    cmd->add_option("--isolated", o->pipeline.isolated,
                    "isolated particles (no neighbour within h), which the field leaves out: "
                    "spheres (each a closed icosphere of its radius, faces within 1% of it) or "
                    "drop (left out of the mesh)")
        ->capture_default_str()
        ->check(CLI::IsMember({"spheres", "drop"}));
    addAttributesOption(cmd, o->pipeline,
                        "written as PLY vertex properties (v as vx vy vz) or VTK point data, not "
                        "into OBJ; with --vdb also as grids over the level set's band");
    cmd->add_option("--sphere-deviation", o->pipeline.params.post.sphereDeviation,
                    "how far the spheres' faces may dip inside their radius, as a fraction of it; "
                    "picks the icosphere level (0.01: 1,280 triangles, 0.05: 320)")
        ->capture_default_str()
        ->check(CLI::Range(1e-6, 0.5));
    addPostOptions(cmd, o->pipeline);
    cmd->get_option("--raw")->excludes(
        cmd->add_option("--volume", o->pipeline.volume,
                        "what each closed component's volume is brought to after decimation, "
                        "smoothing and subdivision (an offset of at most 0.3 voxel): particles "
                        "(those inside it, N (2r)^3: SPH's fluid volume; SSP07's raw surface "
                        "holds 80-95% of it) or mesh (what marching cubes enclosed)")
            ->capture_default_str()
            ->check(CLI::IsMember({"mesh", "particles"})));
    cmd->get_option("--raw")->excludes(
        cmd->add_option("--cover", o->pipeline.params.post.cover,
                        "on or off: the last step covers the particle centres the surface "
                        "leaves outside (SSP07 pulls thin tips in past their last particles), "
                        "each up to a voxel out, by a smooth bump 2.5 voxels wide that ends "
                        "0.1 voxel past it; the rest of the surface does not move")
            ->default_str("on")
            ->check(CLI::IsMember({"on", "off"})));
    cmd->footer(
        "Examples:\n"
        "  fluidsurf reconstruct frame.bgeo -r 0.025 -o frame.obj\n"
        "  fluidsurf reconstruct frame.bgeo -r 0.025 -o raw.obj --raw\n"
        "  fluidsurf reconstruct frame.bgeo -r 0.025 -o frame.obj --vdb frame.vdb --check\n"
        "  fluidsurf reconstruct 'sim/f_{:04}.bgeo' -r 0.025 -o 'obj/f_{:04}.obj' --frames 1-100\n"
        "  fluidsurf reconstruct frame.bgeo -o frame.obj -v --stats frame.json   (r estimated)\n"
        "  fluidsurf reconstruct frame.bgeo -r 0.025 -o frame.ply --adaptive --vdb frame.vdb\n"
        "  fluidsurf reconstruct frame.bgeo -r 0.025 -o frame.ply --attributes v,density,id\n"
        "  fluidsurf reconstruct frame.bgeo -r 0.025 -o frame.ply --flatten off\n"
        "      (flat water keeps the particles' wide bumps: the smoothing's 6 rounds only)\n"
        "  fluidsurf reconstruct frame.bgeo -r 0.025 -o frame.ply --field ssp07-aniso --smooth 20\n"
        "      (kernels stretched along the surface, CPU or CUDA: on strongly jittered flat\n"
        "      water flatter still than the default, on mildly jittered water not)\n"
        "  fluidsurf reconstruct 'sim/f_{:04}.bgeo' -r 0.025 -o 'ply/f_{:04}.ply' --shard 3/8 \\\n"
        "      --skip-existing --keep-going     (the 3rd of 8 tasks; re-runs skip finished "
        "frames)\n"
        "  fluidsurf reconstruct 'sim/f_{:04}.bgeo' -r 0.025 -o 'ply/f_{:04}.ply' --shard slurm\n"
        "      (in sbatch --array=1-100: the frame numbered $SLURM_ARRAY_TASK_ID)\n"
        "The same field as 'rasterize' (all its options), then marching cubes.\n"
        "Ctrl-C stops cleanly (exit code 130): no partial file is left.");
    return [o]() {
        const PipelineOptions& po = o->pipeline;
        auto jobs = planMeshJobs(*o);
        std::vector<FrameJob> vdbJobs;
        if (!o->vdb.empty()) vdbJobs = planVdbFrames(o->input, o->vdb, o->frames, "--vdb");
        std::vector<std::string> outputs = outputsOf(jobs), vdbOutputs = outputsOf(vdbJobs);
        outputs.insert(outputs.end(), vdbOutputs.begin(), vdbOutputs.end());
        checkRunFiles(inputsOf(jobs), outputs, po.stats);
        useHugePagesFor(inputBytes(jobs, shardOf(jobs, o->sequence.shard)), po.threads,
                        interrupted);
        ReconstructParams params = po.resolved();
        params.keepGrids = !vdbJobs.empty(); // without --vdb it goes before post-processing
        const std::vector<std::string> gridAttributes =
            vdbJobs.empty() ? std::vector<std::string>() : params.attributes;
        if (!params.attributes.empty() && !jobs.empty() &&
            io::meshFormatFromPath(jobs[0].output) == io::MeshFormat::Obj) {
            std::fprintf(stderr,
                         "fluidsurf: warning: OBJ cannot hold vertex attributes: --attributes "
                         "is not written to %s (write .ply or .vtk)\n",
                         jobs[0].output.c_str());
            params.attributes.clear();
        }
        Context ctx;
        const auto threadLimit = po.setUp(ctx);
        io::ReadOptions ro;
        ro.dropNonFinite = o->dropNonFinite;
        const std::vector<size_t> picked = shardOf(jobs, o->sequence.shard);
        SequenceRun run(o->sequence, po.quiet);
        const std::vector<size_t> todo = run.unfinished(picked, [&](size_t i) {
            return vdbJobs.empty() ? std::vector<std::string>{jobs[i].output}
                                   : std::vector<std::string>{jobs[i].output, vdbJobs[i].output};
        });
        // the CUDA context (0.1-0.3 s) made while the first frame is read, where it may be used
        if (worthPreparingDevice(ctx, jobs, todo)) prepareDevice(ctx.device());
        Progress bar(picked.size(), "reconstruct", po.quiet);
        Report report(po);
        FrameRun pr{po, jobs, todo, o->inFlight, run, bar};
        using Frame = ParticleFrame<ReconstructResult>;
        runParticleFrames<ReconstructResult>(
            pr, ro, params,
            [&](Frame& f) {
                const std::string& input = jobs[f.job].input;
                f.result = reconstruct(f.particles, f.params, f.ctx, input);
                // What write needs of the particles: the .vdb's attribute grids, the warning of
                // a frame without surface. Otherwise they go now, not a frame later.
                if (vdbJobs.empty() && f.result.field.activeVoxels > 0 && !f.result.mesh.empty())
                    f.particles = ParticleSet();
            },
            [&](Frame& f) {
                const size_t i = f.job;
                const ReconstructResult& res = f.result;
                // The frame's .vdb and mesh appear together, after both were written.
                io::OutputGroup outputs;
                if (!vdbJobs.empty()) {
                    openvdb::GridPtrVec grids = res.adaptiveGrid.empty()
                                                    ? openvdb::GridPtrVec{res.levelSet}
                                                    : res.adaptiveGrid.grids();
                    const openvdb::GridPtrVec more = attributeGrids(
                        f.particles, gridAttributes, *res.levelSet,
                        f.params.fieldParams(f.params.radius).influenceRadius, f.ctx);
                    grids.insert(grids.end(), more.begin(), more.end());
                    const auto t = f.ctx.scope("write vdb");
                    io::writeLevelSet(grids, outputs.add(vdbJobs[i].output));
                }
                if (!po.quiet && !bar.enabled() &&
                    (res.field.isolated || f.readInfo.droppedNonFinite))
                    std::printf("%s: %zu isolated particles %s, %zu non-finite dropped\n",
                                jobs[i].input.c_str(), res.field.isolated,
                                isolatedFate(f.params, res).c_str(), f.readInfo.droppedNonFinite);
                warnIfEmpty(jobs[i].input, f.particles, res.field, f.params.radius,
                            res.mesh.empty());
                std::vector<std::pair<std::string, double>> counts = fieldCounts(res.field);
                if (res.adaptiveGrid.empty())
                    counts.push_back({"surface_cells", double(res.meshing.surfaceCells)});
                else
                    addAdaptiveCounts(res.adaptiveMesh, counts, false);
                addPostCounts(res.post, counts);
                counts.push_back({"isolated_spheres", double(res.isolatedSpheres)});
                writeAndReport(*o, f.ctx, res.mesh, jobs[i], bar.enabled(), report, outputs, counts,
                               &res.field, res.vertexAttributes);
                stopIfInterrupted(f.ctx);
            });
        bar.finish();
        report.finish();
        return run.finish("reconstruct", picked.size());
    };
}

} // namespace cli
} // namespace fluidsurf
