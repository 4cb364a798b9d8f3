// InfoCommand.cc - `fluidsurf info FILE...`: format, count, attributes, bounds, spacing estimate.
#include "Commands.h"
#include "Frames.h"

#include <fluidsurf/SpacingEstimate.h>
#include <fluidsurf/io/ParticleIO.h>

#include <cstdio>
#include <memory>

namespace fluidsurf {
namespace cli {

namespace {

struct InfoOptions
{
    std::vector<std::string> files;
    std::string frames;
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

} // namespace

Runner addInfoCommand(CLI::App& app)
{
    auto o = std::make_shared<InfoOptions>();
    CLI::App* cmd = app.add_subcommand(
        "info", "Show what a particle file holds: format, count, attributes, bounds, spacing");
    cmd->add_option("files", o->files, "particle files or frame patterns")->required();
    cmd->add_option("--frames", o->frames, "frame range A-B for a pattern");
    cmd->add_flag("--drop-nonfinite", o->dropNonFinite,
                  "drop particles with NaN/Inf coordinates instead of failing");
    cmd->add_flag("--no-spacing", o->noSpacing, "skip the nearest-neighbour spacing estimate");
    cmd->footer("Example: fluidsurf info frame.bgeo 'sim/fluid_{:04}.vtk' --frames 1-3");
    return [o]() {
        for (const std::string& f : o->files)
            for (const FrameJob& job : planFrames(f, "", o->frames))
                printInfo(job.input, *o);
        return 0;
    };
}

} // namespace cli
} // namespace fluidsurf
