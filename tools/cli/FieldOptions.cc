// FieldOptions.cc - field options, radius choice and Params for rasterize and reconstruct.
#include "FieldOptions.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/SpacingEstimate.h>

#include <sys/resource.h>

#include <algorithm>
#include <cstdio>

namespace fluidsurf {
namespace cli {

bool endsWith(const std::string& s, const std::string& suffix)
{
    return s.size() >= suffix.size() &&
           s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}

std::unique_ptr<tbb::global_control> limitThreads(int threads)
{
    if (threads <= 0) return nullptr;
    return std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism,
                                                 threads);
}

double peakRssMiB()
{
    rusage u{};
    getrusage(RUSAGE_SELF, &u);
    return double(u.ru_maxrss) / 1024.0;
}

void printDevice(const RasterizeStats& s)
{
    std::printf("  field on %s", s.device.c_str());
    if (!s.gpuStages.empty()) {
        std::printf(" (CUDA events:");
        for (const StageTime& st : s.gpuStages)
            std::printf(" %s %.2f ms", st.name.c_str(), st.seconds * 1e3);
        std::printf("; %.1f MiB of device memory)", double(s.gpuBytes) / (1 << 20));
    }
    std::printf("\n");
}

double chooseRadius(const FieldOptions& o, const ParticleSet& ps, bool print)
{
    if (o.radius > 0) return o.radius;
    if (!o.ignoreRadiusAttribute)
        if (const Attribute* a = ps.find(AttributeRole::Radius)) {
            const float r =
                a->floats.empty() ? 0.f : *std::max_element(a->floats.begin(), a->floats.end());
            if (r > 0) {
                if (print)
                    std::printf("radius r = %g (largest value of the attribute '%s')\n", r,
                                a->name.c_str());
                return r;
            }
        }
    const SpacingEstimate est = estimateSpacing(ps);
    if (!(est.radius > 0))
        throw ValueError("cannot estimate the particle radius (fewer than two particles, or all "
                         "isolated); pass -r");
    if (print)
        std::printf(
            "radius r ~ %g (ESTIMATE: half the median nearest-neighbour distance; pass -r with the "
            "simulator's radius)\n",
            est.radius);
    return est.radius;
}

void addFieldOptions(CLI::App* cmd, FieldOptions& o)
{
    cmd->add_option("-r,--radius", o.radius,
                    "particle radius r = half the rest spacing, world units "
                    "(default: the radius attribute, else an estimate)");
    auto rel = [&](const char* name, double& v, const char* text) {
        cmd->add_option(name, v, text)->capture_default_str()->check(CLI::PositiveNumber);
    };
    rel("--voxel", o.voxel, "voxel (Marching Cubes cell) size, in r");
    rel("--influence", o.influence, "influence radius R of the field kernel, in r");
    rel("--smoothing-length", o.smoothing, "SPH smoothing length h for neighbour counts, in r");
    rel("--band", o.band,
        "narrow band half width around surface particles, in r (at least 1 + voxel)");
    rel("--half-width", o.halfWidth, "level-set background, in voxels");
    cmd->add_option("--t-low", o.tLow, "SSP07 t_low")->capture_default_str();
    cmd->add_option("--t-high", o.tHigh, "SSP07 t_high")->capture_default_str();
    cmd->add_option("--surface-neighbours", o.surfaceNeighbours,
                    "fewer neighbours within h: surface particle")
        ->capture_default_str();
    cmd->add_option("--splash-neighbours", o.splashNeighbours,
                    "fewer neighbours within h: splash particle")
        ->capture_default_str();
    cmd->add_option("--color-field", o.colorField, "color field below this: surface particle")
        ->capture_default_str();
    cmd->add_option("--field", o.field, "ssp07 or zb05")
        ->capture_default_str()
        ->check(CLI::IsMember({"ssp07", "zb05"}));
    cmd->add_option("--method", o.method, "narrow-band, or the baselines gather-full and scatter")
        ->capture_default_str()
        ->check(CLI::IsMember({"narrow-band", "gather-full", "scatter"}));
    cmd->add_option("--device", o.device,
                    "cpu, cuda (the narrow band on the GPU: sort, classify, band and gather; "
                    "gather-full gathers there) or auto (cuda when a usable GPU is present)")
        ->capture_default_str()
        ->check(CLI::IsMember({"cpu", "cuda", "auto"}));
    cmd->add_flag("--ignore-radius-attribute", o.ignoreRadiusAttribute,
                  "use r for every particle even with pscale");
    cmd->add_flag("--keep-isolated", o.keepIsolated,
                  "isolated particles become spheres of radius r in the grid");
}

Params makeParams(const FieldOptions& o, double radius)
{
    Params p = Params::fromRadius(radius);
    p.voxelSize = o.voxel * radius;
    p.influenceRadius = o.influence * radius;
    p.smoothingLength = o.smoothing * radius;
    p.bandWidth = o.band * radius;
    p.halfWidth = o.halfWidth;
    p.tLow = o.tLow, p.tHigh = o.tHigh;
    p.surfaceNeighbours = o.surfaceNeighbours, p.splashNeighbours = o.splashNeighbours;
    p.colorFieldThreshold = o.colorField;
    p.perParticleRadii = !o.ignoreRadiusAttribute;
    p.keepIsolated = o.keepIsolated;
    p.field = fieldFromName(o.field);
    p.method = methodFromName(o.method);
    p.device = deviceFromName(o.device);
    return p;
}

void prepareDevice(const FieldOptions& o)
{
    fluidsurf::prepareDevice(deviceFromName(o.device));
}

} // namespace cli
} // namespace fluidsurf
