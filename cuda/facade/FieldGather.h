// FieldGather.h - the SSP07 / ZB05 gather on the GPU (host facade, no CUDA syntax): every active
// voxel of the given leaf blocks gathers the particles within R and stores phi, with the CPU's
// sums to the bit (lib/src/field/GatherField.h: the same picks, order, lanes and fused
// multiply-adds, where the CPU sums on 8 lanes) and the same formula (lib/src/field/FieldMath.h).
//
// Inputs are plain arrays the host builds from its cell index and band topology: particles in
// cell order with the ranges and hash table of the occupied cells, and per leaf the voxel index
// of its corner and 8 words of active bits (word x, bit y * 8 + z). One CUDA block per leaf: the
// block gathers and sorts its leaf's particles as the CPU does (field/GatherLayout.h), and 8
// threads, one a lane, sum each active voxel.
#pragma once

#include <fluidsurf/Vec3.h>

#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

namespace fluidsurf {
namespace cuda {

/// The field's parameters (fluidsurf::Params), lengths in world units.
struct FieldSettings
{
    double voxelSize = 0, influenceRadius = 0, radius = 0, tLow = 0.4, tHigh = 3.5;
    double radiusScale = 1; ///< Params::radiusScale
    bool density = false;   ///< Params::field is Yt10 (AnisotropicInput::weight)
    double isoLevel = 0.5;  ///< Params::isoLevel
    float background = 0;
    bool ssp07 = true;
};

struct GatherInput
{
    const Vec3f* positions = nullptr; ///< particles in cell order
    const float* radii = nullptr;     ///< per particle, or null for the uniform radius
    size_t particleCount = 0;
    const uint32_t* cellStarts = nullptr; ///< cellCount + 1 offsets into the particles
    size_t cellCount = 0;
    /// The cell index's hash table (neighbors::CellIndex): Morton key per slot (~0 when empty)
    /// and the cell it names; tableSize is a power of two.
    const uint64_t* tableKeys = nullptr;
    const uint32_t* tableCells = nullptr;
    size_t tableSize = 0;
    double cellSize = 0, cellOrigin[3] = {0, 0, 0};
    uint32_t cellDims[3] = {0, 0, 0};
    const int32_t* leafOrigins = nullptr; ///< 3 per leaf: voxel index of the leaf's corner
    const uint64_t* leafActive = nullptr; ///< 8 per leaf: active voxels
    size_t leafCount = 0;
    FieldSettings field;
};

struct GatherTimes
{
    double uploadMs = 0, kernelMs = 0, downloadMs = 0; ///< CUDA events on the stream
    size_t deviceBytes = 0;                            ///< device memory allocated
};

/// Whether the device gather runs at this voxel size and support radius: it keeps a counter for
/// each of a leaf's slab-and-column bins in shared memory, which grows with (R / voxel size)^3
/// above 16 slabs an axis; past the device's limit (R of about 100 voxels on an H100) the CPU's
/// field is used. False also without a usable device.
bool gatherFits(double voxelSize, double influenceRadius);

/// phi at the active voxels of the leaves, leaf after leaf in OpenVDB's voxel order (as many
/// values as the masks have bits: a thin band fills a leaf to some 15%, and only these travel
/// back). Throws fluidsurf::Error on CUDA errors.
std::vector<float> gatherField(const GatherInput& input, GatherTimes* times = nullptr,
                               void* stream = nullptr);

/// The ssp07-aniso and yt10 fields' kernels (lib/src/field/AnisotropicField.h): gather.positions
/// are their centres in cell order (gather.radii their radii or null), and per kernel in that order
struct AnisotropicInput
{
    GatherInput gather;            ///< (its leaves are evaluate()'s)
    const float* a = nullptr;      ///< 6 a kernel: A' = R^2 G^2 (xx, xy, xz, yy, yz, zz)
    const float* extent = nullptr; ///< 3 a kernel: its box's half extents, world units
    /// yt10 (field.density): 1 a kernel, V_j W's factor, summed where the radii would be
    const float* weight = nullptr;
    double reach = 0; ///< the most any kernel reaches, world units
    /// Packed (non-null; backend/PackKernels.h): bit j % 32 of fresh[j / 32] is set where kernel
    /// j's a, extent and weight differ from kernel j - 1's (kernel 0's always), and a, extent and
    /// weight hold only those kernels' entries, in order; freshBefore[w] counts the bits set in
    /// the words before w. A frame's interior kernels are one sphere, so most repeat the kernel
    /// before them and three quarters of the upload stay on the host.
    const uint32_t* fresh = nullptr;
    const uint32_t* freshBefore = nullptr;
    size_t freshCount = 0; ///< the bits set: the entries a, extent and weight hold
};

/// The ssp07-aniso gather on the device (AnisotropicGather.cu): the kernels uploaded once, then
/// phi for the leaves of each evaluate() (the band, then each round of its completion), as
/// gatherField returns them, with the CPU's bits. Throws fluidsurf::Error on CUDA errors.
class AnisotropicGather
{
public:
    explicit AnisotropicGather(const AnisotropicInput& in);
    ~AnisotropicGather();
    AnisotropicGather(const AnisotropicGather&) = delete;
    AnisotropicGather& operator=(const AnisotropicGather&) = delete;

    /// phi at the active voxels, leaf after leaf in voxel order (as many as the masks' bits);
    /// times: this call's, the kernels' upload counted in the first.
    std::vector<float> evaluate(const int32_t* leafOrigins, const uint64_t* leafActive,
                                size_t leafCount, GatherTimes* times = nullptr);

private:
    struct Impl;
    std::unique_ptr<Impl> mImpl;
};

} // namespace cuda
} // namespace fluidsurf
