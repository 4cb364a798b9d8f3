// Uses the installed library as a tool builder would: generate a scene, write it, read it back,
// and reconstruct its surface with the one library call, checking the mesh with the library's
// own checker.
#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/Scenes.h>
#include <fluidsurf/Version.h>
#include <fluidsurf/io/ParticleIO.h>

#include <cstdio>

int main(int argc, char** argv)
{
    if (argc < 2) return 2;
    fluidsurf::SceneParams p;
    p.count = 1000;
    fluidsurf::io::writeParticles(fluidsurf::generateScene(fluidsurf::Scene::Block, p), argv[1]);
    const fluidsurf::ParticleSet ps = fluidsurf::io::readParticles(argv[1]);
    fluidsurf::Context ctx;
    const fluidsurf::ReconstructResult res =
        fluidsurf::reconstruct(ps, fluidsurf::ReconstructParams::fromRadius(p.radius), ctx);
    const fluidsurf::MeshReport report = fluidsurf::checkMesh(res.mesh);
    std::printf("downstream read %zu particles with fluidsurf %s; mesh: %s\n", ps.size(),
                FLUIDSURF_VERSION_STRING, fluidsurf::describe(report).c_str());
    return ps.size() == 1000 && report.watertight() && report.volume > 0 &&
                   res.levelSet->activeVoxelCount() > 0
               ? 0
               : 1;
}
