// Uses the installed library: generate a scene, write it, read it back.
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
    std::printf("downstream read %zu particles with fluidsurf %s\n", ps.size(), FLUIDSURF_VERSION_STRING);
    return ps.size() == 1000 ? 0 : 1;
}
