// Stages.cuh - the device stages of the narrow-band pipeline, one .cu file each, run in order
// on one stream by NarrowBandPipeline.cu. Plain device arrays in, plain device arrays out.
#pragma once

#include "DeviceCells.cuh"
#include "DeviceMemory.cuh"
#include "classify/ClassRule.h"
#include "field/FieldMath.h"

#include "facade/FieldGather.h"

#include <cstdint>

namespace fluidsurf {
namespace cuda {

// --- CellIndex.cu (neighbors/CellIndex): Morton keys, radix sort, cell ranges, hash table --------

/// Bounds of n positions (float min and max per axis) into lo/hi on the host (synchronises).
void particleBounds(const float3* positions, size_t n, float lo[3], float hi[3], DeviceMemory& mem,
                    cudaStream_t stream);

/// Sort the n uploaded particles (radii may be null) into the cell grid given by cells.cellSize,
/// origin and dims (computed on the host with the CPU's arithmetic) and fill the rest of cells.
/// Keys and order within a cell match the CPU exactly (stable sort of the input indices).
void sortIntoCells(DeviceCells& cells, const float3* positions, const float* radii, size_t n,
                   DeviceMemory& mem, cudaStream_t stream, StageEvents& events);

// --- Classify.cu (classify/Classify; compiled without FMA contraction: bit-identical to the CPU) -

struct ClassifySettings
{
    float h2 = 0;               ///< float(h * h)
    double smoothingLength = 0; ///< h
    float uniformVolume = 0;    ///< float((2r)^3)
    classify::ClassRule rule;
};

/// classes[i] for every particle (cell order); counts[4] per class come back to the host.
void classifyParticles(const DeviceCells& cells, const ClassifySettings& s, uint8_t* classes,
                       unsigned long long counts[4], DeviceMemory& mem, cudaStream_t stream);

/// Input indices of the isolated particles (unsorted), and, when drop is set, those particles
/// moved out of reach of every voxel so that the gather skips them.
void takeIsolated(DeviceCells& cells, const uint8_t* classes, size_t isolatedCount, bool drop,
                  std::vector<uint32_t>& indices, DeviceMemory& mem, cudaStream_t stream);

// --- NarrowBand.cu (narrowband/NarrowBand) (no FMA contraction: the same voxel ranges as the CPU)

struct BandSettings
{
    double width = 0, invDx = 0;
    bool isolatedSeeds = false; ///< keepIsolated: isolated particles seed the band too
};

/// Leaf keys packed as 21 bits per axis, biased by 2^20 leaves.
constexpr int kLeafBias = 1 << 20;

struct DeviceLeaves
{
    size_t count = 0;
    int32_t* origins = nullptr;          ///< 3 per leaf: voxel index of the corner
    unsigned long long* masks = nullptr; ///< 8 per leaf: word x, bit y * 8 + z
};

/// The leaves and active voxels of the band: every voxel within +-width (per axis) of a seed.
DeviceLeaves markBand(const DeviceCells& cells, const uint8_t* classes, const BandSettings& s,
                      DeviceMemory& mem, cudaStream_t stream);

// --- GatherField.cu (field/GatherField) ----------------------------------------------------------

/// FieldMath's constants from the facade's settings.
field::FieldConstants fieldConstants(const FieldSettings& s, bool perParticleRadii);

/// The cell index of in (its particles, cell ranges and hash table) on the device.
DeviceCells uploadCells(const GatherInput& in, DeviceMemory& mem);

/// phi for the 512 voxels of every leaf into out (leaf after leaf; inactive: background); or,
/// with compactOffsets (per leaf, the number of active voxels in the leaves before it), only the
/// active voxels, leaf after leaf in voxel order: a thin band fills ~15% of its leaves, so this
/// is what goes back to the host. The CPU's sums, bit for bit (GatherField.cu); synchronises
/// once (the leaves' particle counts size the scratch). Throws where gatherFits is false.
void gatherLeaves(const DeviceCells& cells, const int32_t* origins, const unsigned long long* masks,
                  size_t leafCount, double voxelSize, const field::FieldConstants& constants,
                  float* out, DeviceMemory& mem, cudaStream_t stream,
                  const uint32_t* compactOffsets = nullptr);

/// Per leaf, the active voxels of the leaves before it (leafCount + 1 entries, the last is the
/// total, which also comes back to the host; synchronises).
uint32_t* activeOffsets(const unsigned long long* masks, size_t leafCount, size_t& total,
                        DeviceMemory& mem, cudaStream_t stream);

} // namespace cuda
} // namespace fluidsurf
