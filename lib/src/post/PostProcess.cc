// PostProcess.cc - the post-processing steps in their order (see PostProcess.h).
#include <fluidsurf/Error.h>
#include <fluidsurf/PostProcess.h>

#include "post/LoopSubdivision.h"

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

void validate(const PostProcessParams& p)
{
    if (p.subdivide < 0 || p.subdivide > 3)
        throw ValueError("subdivision steps " + std::to_string(p.subdivide) +
                         " (0 to 3: each multiplies the triangles by 4)");
    if (!(p.sphereDeviation > 0 && p.sphereDeviation <= 0.5))
        throw ValueError("sphere deviation " + std::to_string(p.sphereDeviation) +
                         " (a fraction of r in (0, 0.5])");
}

TriangleMesh postProcessMesh(TriangleMesh mesh, const PostProcessParams& params, Context& ctx)
{
    validate(params);
    for (int step = 0; step < params.subdivide; ++step) {
        const auto t = ctx.scope("subdivide");
        mesh = post::loopSubdivide(mesh);
        ctx.throwIfCancelled();
    }
    return mesh;
}

} // namespace fluidsurf
