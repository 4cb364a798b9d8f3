// PostProcess.cc - the post-processing steps in their order (see PostProcess.h).
#include <fluidsurf/Error.h>
#include <fluidsurf/PostProcess.h>

#include "post/Decimate.h"
#include "post/LoopSubdivision.h"
#include "post/OpenMeshDecimate.h"
#include "util/Vec3d.h"

#include <cmath>

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
    if (p.subdivide < 0 || p.subdivide > 3)
        throw ValueError("subdivision steps " + std::to_string(p.subdivide) +
                         " (0 to 3: each multiplies the triangles by 4)");
    if (!(p.sphereDeviation > 0 && p.sphereDeviation <= 0.5))
        throw ValueError("sphere deviation " + std::to_string(p.sphereDeviation) +
                         " (a fraction of r in (0, 0.5])");
}

namespace {

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
                             PostProcessStats* stats)
{
    validate(params);
    PostProcessStats st;
    st.inputTriangles = st.decimatedTriangles = mesh.triangles.size();
    if (params.decimate > 0 || params.decimateError > 0) {
        const auto t = ctx.scope("decimate");
        const size_t target =
            params.decimate > 0
                ? size_t(std::ceil(double(mesh.triangles.size()) * (1 - params.decimate)))
                : 0;
        if (params.decimator == Decimator::OpenMesh) {
            mesh = post::decimateOpenMesh(mesh, target);
        } else {
            const double voxel = params.voxelSize > 0 ? params.voxelSize : meanEdgeLength(mesh);
            post::DecimateTarget to{target};
            if (params.decimateError > 0) to.maxDrift = params.decimateError * voxel;
            post::DecimateStats ds;
            mesh = post::decimate(mesh, to, &ds);
            st.decimateError = voxel > 0 ? ds.maxDrift / voxel : 0;
        }
        st.decimatedTriangles = mesh.triangles.size();
        ctx.throwIfCancelled();
    }
    for (int step = 0; step < params.subdivide; ++step) {
        const auto t = ctx.scope("subdivide");
        mesh = post::loopSubdivide(mesh);
        ctx.throwIfCancelled();
    }
    if (stats) *stats = st;
    return mesh;
}

} // namespace fluidsurf
