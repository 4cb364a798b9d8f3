// MeshLevelSet.cc - the mesh stage (fluidsurf/MeshLevelSet.h): mesher choice, the backend that
// runs marching cubes (backend/Backend.h), under the context's threads and timing.
#include <fluidsurf/Error.h>
#include <fluidsurf/MeshLevelSet.h>

#include "backend/Backend.h"
#include "mesh/VolumeToMesh.h"

#include "util/Threads.h"

namespace fluidsurf {

const char* mesherName(Mesher m)
{
    return m == Mesher::MarchingCubes ? "mc" : "openvdb";
}

Mesher mesherFromName(const std::string& name)
{
    if (name == "mc") return Mesher::MarchingCubes;
    if (name == "openvdb") return Mesher::OpenVdb;
    throw ValueError("unknown mesher '" + name + "' (mc, openvdb)");
}

TriangleMesh meshLevelSet(const openvdb::FloatGrid& grid, Mesher mesher, Context& ctx,
                          MeshStats* stats, RawNormals normals)
{
    if (!grid.transform().isLinear())
        throw ValueError("grid '" + grid.getName() +
                         "' has a non-linear (frustum) transform; only linear ones are meshed");
    const auto timer = ctx.scope("mesh");
    size_t cells = 0;
    std::string device = "cpu";
    TriangleMesh m = util::withThreads(ctx, [&] {
        if (mesher == Mesher::MarchingCubes) {
            std::string reason;
            bool gpu = false;
            if (ctx.device() != Device::Cpu) {
                const auto t = ctx.scope("cuda context"); // made once; waited for, if under way
                gpu = backend::cudaUsable(&reason);
            }
            TriangleMesh mc;
            backend::runOn(ctx.device(), gpu, reason, device, [&](backend::Backend& b) {
                if (b.marchingCubes(grid, normals, ctx, mc, cells)) return;
                backend::makeCpuBackend()->marchingCubes(grid, normals, ctx, mc, cells);
                device = "cpu (the band lies beyond the GPU's leaf keys)";
            });
            return mc;
        }
        TriangleMesh vdb = mesh::openvdbVolumeToMesh(grid, ctx);
        if (normals == RawNormals::None) std::vector<Vec3f>().swap(vdb.normals);
        return vdb;
    });
    if (stats) {
        stats->device = device;
        stats->surfaceCells = cells;
        stats->vertices = m.points.size();
        stats->triangles = m.triangles.size();
    }
    return m;
}

TriangleMesh meshLevelSet(const openvdb::FloatGrid& grid, Mesher mesher, MeshStats* stats)
{
    Context ctx;
    return meshLevelSet(grid, mesher, ctx, stats);
}

} // namespace fluidsurf
