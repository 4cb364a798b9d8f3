// GenerateCommand.cc - `fluidsurf generate SCENE -o FILE`: deterministic test scenes.
#include "Commands.h"

#include <fluidsurf/Scenes.h>
#include <fluidsurf/io/ParticleIO.h>

#include <cstdio>
#include <memory>

namespace fluidsurf {
namespace cli {

Runner addGenerateCommand(CLI::App& app)
{
    struct Opts
    {
        std::string scene, output;
        SceneParams p;
    };
    auto o = std::make_shared<Opts>();
    CLI::App* cmd =
        app.add_subcommand("generate", "Write a deterministic particle scene with a known surface");
    cmd->add_option("scene", o->scene, "single | block | ball | slab | drop | sheet | jet")
        ->required()
        ->check(CLI::IsMember(sceneNames()));
    cmd->add_option("-o,--output", o->output,
                    "output particle file (.vdb .bgeo .bgeo.gz .ply .xyz .vtk)")
        ->required();
    cmd->add_option("-r,--radius", o->p.radius, "particle radius r (lattice spacing is 2r)")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    cmd->add_option("-n,--count", o->p.count, "approximate particle count")
        ->capture_default_str()
        ->check(CLI::Range(size_t(1), size_t(1) << 31));
    cmd->add_option("--seed", o->p.seed, "seed for jitter and droplet placement")
        ->capture_default_str();
    cmd->add_option("--jitter", o->p.jitter,
                    "slab: in-plane jitter; sheet, jet: in 3D; in lattice spacings")
        ->capture_default_str()
        ->check(CLI::Range(0.0, 0.49));
    cmd->add_option(
           "--layers", o->p.layers,
           "slab, sheet: thickness in particles; jet: particles across (sheet, jet: 1 to 64)")
        ->capture_default_str()
        ->check(CLI::Range(1, 100000));
    cmd->add_option("--pool-depth", o->p.poolDepthScale, "drop: pool depth multiplier")
        ->capture_default_str()
        ->check(CLI::PositiveNumber);
    cmd->add_option("--pool-aspect", o->p.poolAspect, "drop: pool width / depth")
        ->capture_default_str()
        ->check(CLI::Range(1.0, 1000.0));
    cmd->add_option("--droplets", o->p.droplets, "drop: isolated droplets")
        ->capture_default_str()
        ->check(CLI::Range(0, 1000));
    cmd->footer("Examples:\n"
                "  fluidsurf generate drop --count 1000000 -r 0.01 -o drop_1M.bgeo\n"
                "  fluidsurf generate sheet -n 20000 --layers 1 --jitter 0.2 -o sheet.bgeo\n"
                "  fluidsurf generate jet -n 4000 --layers 2 --jitter 0.1 -o jet.bgeo");
    return [o]() {
        const ParticleSet ps = generateScene(sceneFromName(o->scene), o->p);
        io::writeParticles(ps, o->output);
        std::printf("%s: %s scene, %zu particles, radius %g\n", o->output.c_str(), o->scene.c_str(),
                    ps.size(), o->p.radius);
        return 0;
    };
}

} // namespace cli
} // namespace fluidsurf
