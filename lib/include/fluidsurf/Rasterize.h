// Rasterize.h - particles to a narrow-band SSP07 level set (thesis chapter 4), as an ordinary
// OpenVDB level set: FloatGrid "surface", class GRID_LEVEL_SET, voxel (i,j,k) at (i,j,k) * dx,
// negative inside, background = halfWidth * dx, metadata naming the parameters (DESIGN.md).
// The first half of reconstruct() (Reconstruct.h); meshLevelSet is the second.
//
//   neighbors (Z-order cells) -> classify (surface / interior / splash / isolated)
//   -> narrow band (active voxels near surface particles) -> field (gather) -> complete band
//   -> level set
//
// With Params::adaptive (thesis ch. 6, AdaptiveGrid.h): classified on the CPU, then particle
// curvature, the band at 2 voxels (field, completion), the level map of coarse cells, and the
// points each level needs, all evaluated by the same backend; the result holds the three grids.
//
// The stages up to the field run on the Context's backend (lib/src/backend): the CPU (TBB), or
// with Device::Cuda (or Auto and a GPU) the GPU, which gives the same active voxels, classes and
// values as the CPU, to the bit where the CPU has AVX2 and FMA (else within 1e-5 r: the CPU then
// sums on 4 lanes, field::fieldLanes). Band completion asks the same backend for its new
// voxels. Isolated particles (no neighbour within h) are left out of the grid and listed in the
// result. The output is identical for any thread count (Context::setThreads).
#pragma once

#include <fluidsurf/AdaptiveGrid.h>
#include <fluidsurf/Context.h>
#include <fluidsurf/Params.h>
#include <fluidsurf/ParticleSet.h>

#include <openvdb/openvdb.h>

#include <string>
#include <vector>

namespace fluidsurf {

/// Wall time of one stage (the GPU's own stages, from CUDA events).
struct StageTime
{
    std::string name;
    double seconds = 0;
};

struct RasterizeStats
{
    size_t particles = 0;
    size_t interior = 0, surface = 0, splash = 0, isolated = 0; ///< surface excludes splash
    size_t activeVoxels = 0, leaves = 0;
    size_t fieldEvaluations = 0; ///< vertices at which phi was computed
    size_t bandCompletion = 0;   ///< voxels added where a zero crossing reached the band's edge
    double bandWidth = 0;        ///< half width actually used, world units
    /// Where the field ran: "cpu", the GPU's name, or with Device::Auto "cpu (CUDA failed: why)".
    std::string device = "cpu";
    /// With CUDA: the device's stages (upload, bounds, sort, cells, classify, band, isolated,
    /// gather, download, completion gather; gather-full: upload, gather, download), GPU time from
    /// CUDA events, inside the host stages of the timing tree.
    std::vector<StageTime> gpuStages;
    size_t gpuBytes = 0; ///< peak device memory the CUDA stages held
    /// With Params::adaptive: coarse cells per level (after completion), cells added by the
    /// level-3 completion, level-3 values sub-sampled from level 2 (fluidsurf/AdaptiveGrid.h).
    size_t level2Cells = 0, level3Cells = 0, completionCells = 0, subsampled = 0;
    size_t refinedCells = 0; ///< flat cells refined where level 2 missed (levelTolerance)
    size_t islandCells = 0;  ///< level-2 cells moved to level 3 as islands among level 3
    /// Level-3 values kept at the middle of level-2 edges away from level 3: they place those
    /// edges' vertices (adaptive/LevelFields.h).
    size_t level2CrossingProbes = 0;
};

struct RasterizeResult
{
    openvdb::FloatGrid::Ptr grid;            ///< with Params::adaptive, adaptive.level2
    AdaptiveGrid adaptive;                   ///< with Params::adaptive: all three grids
    std::vector<uint32_t> isolatedParticles; ///< left out of the grid: indices into the input,
                                             ///< ascending (empty with keepIsolated)
    RasterizeStats stats;
};

/// Start looking for the GPU and creating its CUDA context (0.1-0.3 s) on a thread of its own, so
/// that this overlaps reading the particles; a later rasterizeParticles with Device::Cuda or Auto
/// finds it ready. Does nothing for Device::Cpu or without the CUDA backend. Never throws.
/// A program that calls it calls waitForDevice before it ends.
void prepareDevice(Device device);

/// Waits until the look for the GPU that prepareDevice started is over (at once when none was
/// started, or it is over). Call it before the process ends, on error paths too: a process
/// whose exit begins while the CUDA context is still being made can hang there for good (seen
/// on the H100 machine: `reconstruct missing.xyz --device cuda` printed its error and never
/// ended, SIGTERM notwithstanding). Never throws.
void waitForDevice();

/// Particle radii: with params.perParticleRadii and a radius attribute (pscale), r_j comes from
/// it; otherwise r_j = params.radius. sourceName goes into the grid metadata. Stages are timed in
/// ctx.timing() under "rasterize". ValueError for invalid parameters or an input that cannot be
/// gridded; Cancelled when ctx's callback stopped it.
RasterizeResult rasterizeParticles(const ParticleSet& particles, const Params& params, Context& ctx,
                                   const std::string& sourceName = "");

/// The same with a context of its own: CPU, all cores, no callback.
RasterizeResult rasterizeParticles(const ParticleSet& particles, const Params& params,
                                   const std::string& sourceName = "");

/// The metadata names fluidsurf writes, e.g. "fluidsurf:particle_radius".
std::vector<std::string> levelSetMetadataNames();

} // namespace fluidsurf
