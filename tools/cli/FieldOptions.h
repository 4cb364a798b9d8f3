// FieldOptions.h - the field options shared by `rasterize` and `reconstruct`: every Params field,
// lengths relative to the particle radius r, and how r is chosen.
#pragma once

#include <fluidsurf/Params.h>
#include <fluidsurf/ParticleSet.h>
#include <fluidsurf/Rasterize.h>

#include <CLI/CLI.hpp>
#include <tbb/global_control.h>

#include <memory>

#include <string>

namespace fluidsurf {
namespace cli {

struct FieldOptions
{
    std::string field = "ssp07", method = "narrow-band", device = "cpu";
    double radius = 0, voxel = 1, influence = 4, smoothing = 4, band = 2, halfWidth = 3;
    double tLow = 0.4, tHigh = 3.5, colorField = 0.9;
    int surfaceNeighbours = 25, splashNeighbours = 3;
    bool ignoreRadiusAttribute = false, keepIsolated = false;
};

void addFieldOptions(CLI::App* cmd, FieldOptions& o);

/// The radius r: -r, else the radius attribute's largest value, else an estimate. Prints which
/// (an estimate as "ESTIMATE") when print is set.
double chooseRadius(const FieldOptions& o, const ParticleSet& ps, bool print);

Params makeParams(const FieldOptions& o, double radius);

/// With --device cuda or auto: start creating the CUDA context now, while the first frame is read.
void prepareDevice(const FieldOptions& o);

double peakRssMiB();
/// -j: at most threads worker threads while the returned object lives (all cores for <= 0).
std::unique_ptr<tbb::global_control> limitThreads(int threads);
/// With -v: where the field gather ran, and the GPU's own timings when it was a GPU.
void printDevice(const RasterizeStats& stats);
bool endsWith(const std::string& s, const std::string& suffix);

} // namespace cli
} // namespace fluidsurf
