// PostProcess.cc - the post-processing steps in their order (see PostProcess.h): the chain of
// post/'s stages; the smoothing and the test of which particles the surface holds through the
// backend the context asks for (backend/Backend.h: on the GPU with --device cuda or auto, the
// same bytes as on the CPU). Here, above post/, because the backend runs post/'s stages.
#include <fluidsurf/Error.h>
#include <fluidsurf/PostProcess.h>

#include "backend/Backend.h"
#include "post/CoverParticles.h"
#include "post/Decimate.h"
#include "post/LoopSubdivision.h"
#include "post/Normals.h"
#include "post/OpenMeshDecimate.h"
#include "post/ParticleVolumes.h"
#include "post/Smooth.h"
#include "post/Volumes.h"
#include "util/Vec3d.h"

#include <cmath>
#include <functional>
#include <string>

namespace fluidsurf {

const char* isolatedModeName(IsolatedMode m)
{
    return m == IsolatedMode::Drop ? "drop" : "spheres";
}

IsolatedMode isolatedModeFromName(const std::string& name)
{
    if (name == "drop") return IsolatedMode::Drop;
    if (name == "spheres") return IsolatedMode::Spheres;
    throw ValueError("unknown isolated-particle mode '" + name + "' (drop, spheres)");
}

const char* volumeTargetName(VolumeTarget v)
{
    return v == VolumeTarget::Particles ? "particles" : "mesh";
}

VolumeTarget volumeTargetFromName(const std::string& name)
{
    if (name == "mesh") return VolumeTarget::Mesh;
    if (name == "particles") return VolumeTarget::Particles;
    throw ValueError("unknown volume target '" + name + "' (mesh or particles)");
}

const char* decimatorName(Decimator d)
{
    return d == Decimator::Quadric ? "quadric" : "openmesh";
}

Decimator decimatorFromName(const std::string& name)
{
    if (name == "quadric") return Decimator::Quadric;
    if (name == "openmesh") return Decimator::OpenMesh;
    throw ValueError("unknown decimator '" + name + "' (quadric, openmesh)");
}

void validate(const PostProcessParams& p)
{
    if (!(p.decimate >= 0 && p.decimate < 1))
        throw ValueError("decimation fraction " + std::to_string(p.decimate) +
                         " (the share of triangles to remove, in [0, 1); 0 for none)");
    if (!(p.decimateError >= 0 && std::isfinite(p.decimateError)))
        throw ValueError("decimation error bound " + std::to_string(p.decimateError) +
                         " (in voxels, >= 0; 0 for none)");
    if (!(p.voxelSize >= 0 && std::isfinite(p.voxelSize)))
        throw ValueError("voxel size " + std::to_string(p.voxelSize) +
                         " for the decimation error bound (world units, >= 0)");
    if (p.decimator == Decimator::OpenMesh && p.decimateError > 0)
        throw ValueError("the openmesh decimator takes no error bound (its quadric error is a "
                         "sum over planes, not a length); use the quadric decimator");
    if (p.smooth < 0 || p.smooth > 100)
        throw ValueError("smoothing rounds " + std::to_string(p.smooth) + " (0 to 100)");
    if (p.subdivide < 0 || p.subdivide > 3)
        throw ValueError("subdivision steps " + std::to_string(p.subdivide) +
                         " (0 to 3: each multiplies the triangles by 4)");
    if (!(p.sphereDeviation > 0 && p.sphereDeviation <= 0.5))
        throw ValueError("sphere deviation " + std::to_string(p.sphereDeviation) +
                         " (a fraction of r in (0, 0.5])");
}

bool changesMesh(const PostProcessParams& p)
{
    return p.decimate > 0 || p.decimateError > 0 || p.smooth > 0 || p.subdivide > 0;
}

namespace {

// How far each step may move the surface, in voxels: the steps' share of the half voxel that
// the processed mesh may be from the raw one (the fidelity target). Per step, not a
// proof for the whole: decimation's bound holds per collapse, and collapses build on each
// other. Measured on the real frames with these: at most 0.47 voxel after all three steps.
constexpr double kDecimateStep = 0.15; ///< a collapse: see post::DecimateTarget::maxStep
constexpr double kSmoothMove = 0.2;    ///< a point, over all rounds of smoothing
/// a point on flat fluid, over the smoothing and its flattening (post/Smooth.h; a point
/// between flat and curved: 0.2 + 0.2 w^2 for its weight w). The particles' jitter leaves bumps
/// of 0.3-0.5 voxel there: a jittered slab at J = 0.4 came out 0.82-0.87x as bumpy as
/// splashsurf's smoothed mesh with 0.35, 0.53-0.77x with 0.4 (six seeds; before the flat steps
/// took flat neighbours only). Flattening them moves the surface that far from the raw mesh:
/// the large frames' meshes lie up to 0.62 voxel from their raw ones (0.53 with 0.3, 0.45 with
/// 0.2; 0.43 without flattening), the small real frames' up to 0.48 (the steps' half voxel
/// holds with flatten off; PostProcessTest).
constexpr double kFlatMove = 0.4;
constexpr double kLoopMove = 0.1; ///< a point, in one Loop step
/// The most a component is offset to give its volume back (post/Volumes.h): what the steps'
/// bounds let a droplet shrink by, with room to spare.
constexpr double kVolumeOffset = 0.3;
/// Covering the centres left outside (post/CoverParticles.h): each ends this far inside; the
/// bump's radius; centres farther out are left. Measured outside the smoothed surface on the
/// real frames: at most 0.53 voxel on the small ones, 0.84 on the large.
constexpr double kCoverMargin = 0.1, kCoverReach = 2.5, kCoverDepth = 1.0;

double meanEdgeLength(const TriangleMesh& mesh)
{
    double sum = 0;
    for (const auto& t : mesh.triangles)
        for (int k = 0; k < 3; ++k)
            sum += toVec3d(mesh.points[t[(k + 1) % 3]] - mesh.points[t[k]]).length();
    return mesh.triangles.empty() ? 0 : sum / double(3 * mesh.triangles.size());
}

} // namespace

TriangleMesh postProcessMesh(TriangleMesh mesh, const PostProcessParams& params, Context& ctx,
                             PostProcessStats* stats, const ParticleVolumes* particles)
{
    validate(params);
    PostProcessStats st;
    st.inputTriangles = st.decimatedTriangles = mesh.triangles.size();
    const double voxel = params.voxelSize > 0 ? params.voxelSize : meanEdgeLength(mesh);
    if (!changesMesh(params) || mesh.triangles.empty()) {
        if (stats) *stats = st;
        return mesh;
    }
    // each component's volume before the steps, and which component each point is of after
    // each (see post/Volumes.h)
    post::Components before;
    {
        const auto t = ctx.scope("volumes");
        before = post::findComponents(mesh);
    }
    std::vector<uint32_t> component = std::move(before.ofPoint); // (not needed there again)
    // the steps that have a GPU form run on the device the context asks for (the same bytes)
    std::string gpuReason, ranOn;
    const bool gpu = ctx.device() != Device::Cpu && backend::cudaUsable(&gpuReason);
    auto onDevice = [&](const std::function<void(backend::Backend&)>& work) {
        backend::runOn(ctx.device(), gpu, gpuReason, ranOn, work);
    };
    const bool decimating = params.decimate > 0 || params.decimateError > 0;
    if (!decimating) post::markClosed(before, mesh, component);
    if (decimating) {
        const auto t = ctx.scope("decimate");
        const size_t target =
            params.decimate > 0
                ? size_t(std::ceil(double(mesh.triangles.size()) * (1 - params.decimate)))
                : 0;
        if (params.decimator == Decimator::OpenMesh) {
            // its points cannot be traced back: volumes are kept from here on
            mesh = post::decimateOpenMesh(mesh, target, ctx);
            before = post::findComponents(mesh);
            component = before.ofPoint;
            post::markClosed(before, mesh, component);
        } else {
            post::DecimateTarget to{target};
            if (params.decimateError > 0) to.maxDrift = params.decimateError * voxel;
            to.maxStep = kDecimateStep * voxel;
            post::DecimateStats ds;
            std::vector<uint32_t> kept;
            mesh = post::decimate(std::move(mesh), to, &ds, &kept);
            std::vector<uint32_t> next(kept.size());
            for (size_t v = 0; v < kept.size(); ++v)
                next[v] = component[kept[v]];
            component.swap(next);
            post::markClosed(before, mesh, component); // decimation keeps borders: cheaper here
            st.decimateError = voxel > 0 ? ds.maxDrift / voxel : 0;
        }
        st.decimatedTriangles = mesh.triangles.size();
        ctx.throwIfCancelled();
    }
    if (params.smooth > 0) {
        const auto t = ctx.scope("smooth");
        post::SmoothParams sp;
        sp.rounds = params.smooth, sp.maxMove = kSmoothMove * voxel;
        sp.flatten = params.flatten, sp.flatMove = kFlatMove * voxel, sp.voxel = voxel;
        onDevice([&](backend::Backend& b) { b.smoothMesh(mesh, sp, ctx); });
        ctx.throwIfCancelled();
    }
    // Which particles the smoothed surface holds: its components' volume targets, and the
    // centres it leaves outside. Here rather than on the raw mesh: a fifth of its triangles
    // (half the time on the 1.7M-particle frame), and the surface nearest the final one.
    std::vector<Vec3f> outside;
    const bool covering = params.cover && particles;
    if ((params.volume == VolumeTarget::Particles && particles) || covering) {
        const auto t = ctx.scope("particles inside");
        std::vector<uint32_t> of;
        onDevice([&](backend::Backend& b) {
            of = b.componentsOfParticles(mesh, component, before, *particles, voxel, ctx);
        });
        if (params.volume == VolumeTarget::Particles)
            post::useParticleVolumes(before, of, *particles);
        if (covering) outside = post::centresOutside(of, *particles);
    }
    for (int step = 0; step < params.subdivide; ++step) {
        const auto t = ctx.scope("subdivide");
        mesh = post::loopSubdivide(mesh, kLoopMove * voxel);
        ctx.throwIfCancelled();
    }
    const post::VertexTriangles around(mesh);
    {
        const auto t = ctx.scope("volumes");
        post::restoreVolumes(mesh, std::move(component), before, kVolumeOffset * voxel, around);
    }
    if (covering) { // (its scope even with none: the timing tree keeps one shape)
        const auto t = ctx.scope("cover particles");
        post::CoverParams cp;
        cp.margin = kCoverMargin * voxel, cp.reach = kCoverReach * voxel;
        cp.maxDepth = kCoverDepth * voxel;
        const post::CoverStats cs = post::coverParticles(mesh, around, outside, cp);
        st.coveredParticles = cs.covered, st.uncoveredParticles = cs.left;
    }
    computeAngleWeightedNormals(mesh, around);
    if (stats) *stats = st;
    return mesh;
}

} // namespace fluidsurf
