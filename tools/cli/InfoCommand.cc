// InfoCommand.cc - `fluidsurf info FILE...`: what a file holds. Particle files: format, count,
// attributes, bounds, spacing estimate. .vdb files: every grid (name, class, type, voxel size,
// active voxels, bounding box, metadata), then the particles of a points grid. Meshes (.obj, and
// .ply with faces): vertices, triangles and the checkMesh report.
#include "Commands.h"
#include "Frames.h"
#include "Options.h"

#include <fluidsurf/MemoryBudget.h>
#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/SpacingEstimate.h>
#include <fluidsurf/io/LevelSetIO.h>
#include <fluidsurf/io/MeshIO.h>
#include <fluidsurf/io/ParticleIO.h>

#include <cstdio>
#include <memory>

namespace fluidsurf {
namespace cli {

namespace {

struct InfoOptions
{
    std::vector<std::string> files;
    std::string frames, maxMemory;
    bool dropNonFinite = false;
    bool noSpacing = false;
};

std::string grouped(uint64_t v)
{
    std::string s = std::to_string(v);
    for (int i = int(s.size()) - 3; i > 0; i -= 3)
        s.insert(size_t(i), ",");
    return s;
}

void printInfo(const std::string& path, const InfoOptions& o)
{
    io::ReadOptions ro;
    ro.dropNonFinite = o.dropNonFinite;
    ro.allowEmpty = true; // info reports an empty frame rather than failing on it
    io::ReadInfo ri;
    const ParticleSet ps = io::readParticles(path, ro, &ri);
    std::printf("%s\n", path.c_str());
    std::printf("  format      %s (%s)\n", io::formatName(ri.format), ri.detail.c_str());
    std::printf("  file size   %s bytes\n", grouped(ri.fileBytes).c_str());
    std::printf("  particles   %s\n", grouped(ps.size()).c_str());
    if (ri.droppedNonFinite)
        std::printf("  dropped     %zu with NaN/Inf coordinates\n", ri.droppedNonFinite);
    std::printf("  attributes  %s\n", ps.attributes.empty() ? "(none)" : "");
    for (const Attribute& a : ps.attributes) {
        std::string role;
        for (AttributeRole r : {AttributeRole::Radius, AttributeRole::Velocity,
                                AttributeRole::Density, AttributeRole::Id})
            if (ps.find(r) == &a) role = std::string("  [") + roleName(r) + "]";
        std::printf("    %-16s %-7s%s\n", a.name.c_str(), a.typeName(), role.c_str());
    }
    if (ps.empty()) return;
    const BBox3f b = ps.bbox();
    std::printf("  bbox min    (%.6g, %.6g, %.6g)\n", b.min.x, b.min.y, b.min.z);
    std::printf("  bbox max    (%.6g, %.6g, %.6g)\n", b.max.x, b.max.y, b.max.z);
    std::printf("  bbox size   (%.6g, %.6g, %.6g)\n", b.max.x - b.min.x, b.max.y - b.min.y,
                b.max.z - b.min.z);
    if (const Attribute* r = ps.find(AttributeRole::Radius)) {
        float lo = r->floats[0], hi = r->floats[0];
        for (float v : r->floats)
            lo = std::min(lo, v), hi = std::max(hi, v);
        std::printf("  radius      per particle (%s): %.6g .. %.6g\n", r->name.c_str(), lo, hi);
    }
    if (o.noSpacing) return;
    const SpacingEstimate est = estimateSpacing(ps);
    if (est.medianNearest > 0) {
        std::printf(
            "  spacing     median nearest-neighbour distance %.6g (%s particles measured)\n",
            est.medianNearest, grouped(est.sampled).c_str());
        if (est.fromDensity)
            std::printf("              %.6g from the density (disordered particles pair up: their "
                        "nearest distance runs short of the spacing)\n",
                        est.spacing);
        std::printf("  radius r    %.6g (estimate: spacing / 2; prefer the simulator's radius when "
                    "known)\n",
                    est.radius);
        if (est.isolated)
            std::printf("  isolated    %s sampled particles have no neighbour nearby\n",
                        grouped(est.isolated).c_str());
    } else {
        std::printf("  spacing     unknown (fewer than 2 distinct particles)\n");
    }
}

/// Lower-case extension check.
bool hasExtension(const std::string& path, const char* ext)
{
    const std::string e(ext);
    if (path.size() < e.size()) return false;
    for (size_t i = 0; i < e.size(); ++i)
        if (std::tolower(uint8_t(path[path.size() - e.size() + i])) != e[i]) return false;
    return true;
}

/// The grids of a .vdb; true when one of them holds points (then the particle lines follow).
bool printVdb(const std::string& path)
{
    std::vector<std::string> skipped;
    const std::vector<io::GridDescription> grids = io::describeVdb(path, &skipped);
    std::printf("%s\n", path.c_str());
    std::printf("  format      OpenVDB, %zu grid%s\n", grids.size(), grids.size() == 1 ? "" : "s");
    for (const std::string& s : skipped)
        std::printf("  not read    %s\n", s.c_str());
    bool points = false;
    for (const io::GridDescription& g : grids) {
        points |= g.valueType == "ptdataidx32";
        std::printf("  grid        '%s'  class %s, type %s\n", g.name.c_str(), g.gridClass.c_str(),
                    g.valueType.c_str());
        std::printf("    voxel size  (%.6g, %.6g, %.6g)%s\n", g.voxelSize[0], g.voxelSize[1],
                    g.voxelSize[2], g.linear ? "" : " (frustum transform)");
        std::printf("    active      %s voxels in %s leaves\n", grouped(g.activeVoxels).c_str(),
                    grouped(g.leaves).c_str());
        if (g.empty)
            std::printf("    bbox        (empty)\n");
        else
            std::printf("    bbox        [%lld, %lld, %lld] .. [%lld, %lld, %lld] (index space)\n",
                        (long long)g.bboxMin[0], (long long)g.bboxMin[1], (long long)g.bboxMin[2],
                        (long long)g.bboxMax[0], (long long)g.bboxMax[1], (long long)g.bboxMax[2]);
        if (!g.background.empty()) std::printf("    background  %s\n", g.background.c_str());
        for (const auto& m : g.metadata)
            std::printf("    %-28s %s\n", m.first.c_str(), m.second.c_str());
    }
    return points;
}

void printMesh(const std::string& path, const TriangleMesh& mesh)
{
    const MeshReport r = checkMesh(mesh);
    std::printf("%s\n", path.c_str());
    std::printf("  format      %s mesh\n", hasExtension(path, ".obj") ? "OBJ" : "PLY");
    std::printf("  vertices    %s%s\n", grouped(mesh.points.size()).c_str(),
                mesh.normals.empty() ? "" : " (with normals)");
    std::printf("  triangles   %s\n", grouped(mesh.triangles.size()).c_str());
    std::printf("  check       %s\n", describe(r).c_str());
}

void describeFile(const std::string& path, const InfoOptions& o)
{
    if (hasExtension(path, ".vdb")) {
        if (printVdb(path)) printInfo(path, o);
        return;
    }
    if (hasExtension(path, ".obj")) return printMesh(path, io::readMesh(path));
    if (hasExtension(path, ".ply")) {
        // A PLY with faces is a mesh; without, a particle file.
        const TriangleMesh mesh = io::readMesh(path);
        if (!mesh.triangles.empty()) return printMesh(path, mesh);
    }
    printInfo(path, o);
}

} // namespace

Runner addInfoCommand(CLI::App& app)
{
    auto o = std::make_shared<InfoOptions>();
    CLI::App* cmd = app.add_subcommand("info", "Show what a particle file, .vdb or mesh holds");
    cmd->add_option("files", o->files, "particle files, .vdb files, meshes (.obj .ply) or patterns")
        ->required();
    cmd->add_option("--frames", o->frames, "frame range A-B for a pattern");
    cmd->add_flag("--drop-nonfinite", o->dropNonFinite,
                  "drop particles with NaN/Inf coordinates (or past 1e15) instead of failing");
    cmd->add_flag("--no-spacing", o->noSpacing, "skip the nearest-neighbour spacing estimate");
    cmd->add_option("--max-memory", o->maxMemory,
                    "the most memory reading a file may take, e.g. 8G (default: 80% of this "
                    "machine's memory): a file whose header or tree promises more is refused "
                    "with the estimate");
    cmd->footer(
        "Examples:\n"
        "  fluidsurf info frame.bgeo 'sim/fluid_{:04}.vtk' --frames 1-3\n"
        "  fluidsurf info frame.vdb         grids: class, voxel size, active voxels, metadata\n"
        "  fluidsurf info frame.obj         mesh: vertices, triangles, watertightness");
    return [o]() {
        if (!o->maxMemory.empty()) setProcessMemoryBudget(parseMemorySize(o->maxMemory));
        for (const std::string& f : o->files)
            for (const FrameJob& job : planFrames(f, "", o->frames))
                describeFile(job.input, *o);
        return 0;
    };
}

} // namespace cli
} // namespace fluidsurf
