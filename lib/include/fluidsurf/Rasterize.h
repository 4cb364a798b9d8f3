// Rasterize.h - particles to a narrow-band SSP07 level set (thesis chapter 4), as an ordinary
// OpenVDB level set: FloatGrid "surface", class GRID_LEVEL_SET, voxel (i,j,k) at (i,j,k) * dx,
// negative inside, background = halfWidth * dx, metadata naming the parameters (DESIGN.md).
//
//   neighbors (Z-order cells) -> classify (surface / interior / splash / isolated)
//   -> narrow band (active voxels near surface particles) -> field (TBB gather) -> level set
//
// With Params::device cuda (or auto and a GPU) the stages up to the field run on the GPU and
// give the same active voxels and classes; values agree with the CPU's within 1e-5 r.
//
// Isolated particles (no neighbour within h) are left out of the grid and listed in the result.
// The output is identical for any thread count; run under tbb::global_control to limit threads.
#pragma once

#include <fluidsurf/Params.h>
#include <fluidsurf/ParticleSet.h>

#include <openvdb/openvdb.h>

#include <string>
#include <vector>

namespace fluidsurf {

/// Wall time of one pipeline stage.
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
    std::vector<StageTime> stages;
    double totalSeconds() const;
    /// Where the field ran: "cpu", the GPU's name, or with Device::Auto "cpu (CUDA failed: why)".
    std::string device = "cpu";
    /// With CUDA: the device's stages (upload, bounds, sort, cells, classify, band, isolated,
    /// gather, download, completion gather; gather-full: upload, gather, download), GPU time from
    /// CUDA events, inside the host stages above and not in totalSeconds.
    std::vector<StageTime> gpuStages;
    size_t gpuBytes = 0; ///< peak device memory the CUDA stages held
};

struct RasterizeResult
{
    openvdb::FloatGrid::Ptr grid;
    std::vector<uint32_t> isolatedParticles; ///< left out of the grid: indices into the input,
                                             ///< ascending (empty with keepIsolated)
    RasterizeStats stats;
};

/// Start looking for the GPU and creating its CUDA context (0.1-0.3 s) on a thread of its own, so
/// that this overlaps reading the particles; a later rasterizeParticles with Device::Cuda or Auto
/// finds it ready. Does nothing for Device::Cpu or without the CUDA backend. Never throws.
void prepareDevice(Device device);

/// Particle radii: with params.perParticleRadii and a radius attribute (pscale), r_j comes from
/// it; otherwise r_j = params.radius. sourceName goes into the grid metadata.
/// ValueError for invalid parameters or an input that cannot be gridded.
RasterizeResult rasterizeParticles(const ParticleSet& particles, const Params& params,
                                   const std::string& sourceName = "");

/// Write grids to a .vdb (Blosc), atomically (temporary file + rename). The file's UUID is
/// derived from its content, so equal grids give byte-identical files. OutputError on failure.
void writeLevelSet(const openvdb::GridPtrVec& grids, const std::string& path);

/// The metadata names fluidsurf writes, e.g. "fluidsurf:particle_radius".
std::vector<std::string> levelSetMetadataNames();

} // namespace fluidsurf
