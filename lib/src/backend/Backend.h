// Backend.h - the one interface to where the field is computed and meshed (DESIGN.md,
// "Backends"): the CPU (TBB) and CUDA implement the same abstract stages, and the pipeline
// (pipeline/Rasterize.cc, mesh/MeshLevelSet.cc) talks to nothing else. A stage that needs another
// stage's work - band completion evaluating the field at its new voxels - asks the backend, never
// that stage's internals.
//
//   narrowBand  neighbors -> classify -> narrow band -> field: the band with phi
//   useParticles / evaluate   phi at the active voxels of any tree (band completion, the
//               gather-full baseline), for the particles of the last narrowBand or useParticles
//   marchingCubes   a level set's mesh (mesh/MarchingCubes.h; the same bytes on either)
//   smoothMesh      post-processing's smoothing (post/Smooth.h; the same points on either)
//   componentsOfParticles   which mesh component holds each particle (post/ParticleVolumes.h)
//
// Selection, the Auto fallback and its reason live in one place too (selectBackend, runOn).
#pragma once

#include "neighbors/CellIndex.h"
#include "post/ParticleVolumes.h"
#include "post/Smooth.h"

#include <fluidsurf/Context.h>
#include <fluidsurf/Level.h>
#include <fluidsurf/Mesh.h>
#include <fluidsurf/Params.h>
#include <fluidsurf/Rasterize.h>

#include <openvdb/openvdb.h>

#include <functional>
#include <memory>
#include <string>
#include <vector>

namespace fluidsurf {
namespace backend {

/// The particles of one frame: positions, and per-particle radii or empty (params.radius).
struct Particles
{
    const std::vector<Vec3f>& positions;
    const std::vector<float>& radii;
};

/// What the narrow-band stages hand on to band completion and the level set.
struct Band
{
    openvdb::FloatTree::Ptr tree; ///< the band's active voxels, holding phi
    size_t interior = 0, surface = 0, splash = 0, isolated = 0;
    std::vector<uint32_t> isolatedParticles; ///< input indices, ascending (none when kept)
    size_t evaluations = 0;
};

class Backend
{
public:
    virtual ~Backend() = default;

    /// "cpu", or the GPU's name.
    virtual std::string name() const = 0;

    /// The band of half width `width` (effectiveBandWidth) around the surface particles, with
    /// phi at its voxels; timed in ctx under the backend's own stage names. Returns false, having
    /// done nothing, when this backend cannot take the frame, and says why in `whyNot` (the GPU's
    /// leaf keys, or its gather's shared memory).
    virtual bool narrowBand(const Particles& particles, const Params& params, const Level& level,
                            double width, Context& ctx, Band& out, std::string& whyNot) = 0;

    /// Particles indexed on the CPU (the baselines' cell index, isolated ones removed) for
    /// evaluate().
    virtual void useParticles(const neighbors::CellIndex& particles) = 0;

    /// phi at every active voxel of tree. Returns the number of evaluations.
    virtual size_t evaluate(openvdb::FloatTree& tree, const Params& params, const Level& level,
                            Context& ctx) = 0;

    /// The device's own stage times and peak memory (nothing for the CPU).
    virtual void deviceStats(RasterizeStats&) const {}

    /// Our marching cubes of grid into out (timed in ctx under the backend's own stage names);
    /// cells: the cells triangulated. Returns false, having done nothing, when this backend
    /// cannot take the grid (the GPU's leaf keys).
    virtual bool marchingCubes(const openvdb::FloatGrid& grid, RawNormals normals, Context& ctx,
                               TriangleMesh& out, size_t& cells) = 0;

    /// mesh smoothed in place as post::smoothAlongNormals(mesh, params) smooths it, to the bit
    /// (its points only: the triangles stay, the normals go). Throws Error where the device
    /// fails, leaving mesh as it was but for its normals.
    virtual void smoothMesh(TriangleMesh& mesh, const post::SmoothParams& params, Context& ctx) = 0;

    /// post::componentsOfParticles(mesh, ofPoint, c, particles, cellSize): the same answer on
    /// either.
    virtual std::vector<uint32_t> componentsOfParticles(const TriangleMesh& mesh,
                                                        const std::vector<uint32_t>& ofPoint,
                                                        const post::Components& c,
                                                        const ParticleVolumes& particles,
                                                        double cellSize, Context& ctx) = 0;
};

std::unique_ptr<Backend> makeCpuBackend();
/// Error when this build has no CUDA backend or there is no usable GPU.
std::unique_ptr<Backend> makeCudaBackend();

/// Whether this build has the CUDA backend and a usable GPU; reason says why not. The first call
/// creates the CUDA context (0.1-0.3 s); later calls return the same answer at no cost.
bool cudaUsable(std::string* reason = nullptr, std::string* deviceName = nullptr);

/// Device::Auto made concrete for one frame of `particles` while this lives: ctx's device is
/// Cpu where the run is too small for the GPU to pay (autoGpuParticles, at ctx's threads), and
/// Auto again afterwards; any other device is left alone. why(): the reason, "" when nothing
/// changed.
class AutoDevice
{
public:
    AutoDevice(Context& ctx, size_t particles);
    ~AutoDevice();
    AutoDevice(const AutoDevice&) = delete;
    AutoDevice& operator=(const AutoDevice&) = delete;
    const std::string& why() const { return mWhy; }

private:
    Context& mCtx;
    std::string mWhy;
};

/// Run work on the backend that ctx.device() asks for: Cpu; Cuda (Error when there is no usable
/// GPU); Auto (the GPU when usable, else the CPU). With Auto, a CUDA failure other than bad input
/// or a cancel calls fallingBack (if given) and reruns work on the CPU. ranOn: the backend's
/// name, or "cpu (CUDA failed: ...)". gpuUsable and gpuReason are cudaUsable's answer (the
/// caller may overlap it with its own checks).
void runOn(Device device, bool gpuUsable, const std::string& gpuReason, std::string& ranOn,
           const std::function<void(Backend&)>& work,
           const std::function<void()>& fallingBack = nullptr);

/// The same for the field: stats.device, and the device's own stage times.
void runOn(Device device, bool gpuUsable, const std::string& gpuReason, RasterizeStats& stats,
           const std::function<void(Backend&)>& work);

} // namespace backend
} // namespace fluidsurf
