// QualityBench.cc - `fluidsurf_bench quality`: what the surface looks like rather than how fast
// it comes (issue 64): the flatness of a jittered slab's top face, and the volume each mesh
// encloses against the particles' own, for our raw and default pipelines and, in the same run,
// splashsurf with its recommended weighted smoothing (flatness) and raw (volume).
#include "Bench.h"

#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/Scenes.h>
#include <fluidsurf/io/MeshIO.h>
#include <fluidsurf/io/ParticleIO.h>

#include <cmath>
#include <cstdio>
#include <unistd.h>

namespace fluidsurf {
namespace bench {

namespace {

/// The top face of a horizontal slab away from its edges: the vertices over its middle 60%
/// across and above its top particles' centres; RMS of their heights about their mean, and the
/// mean angle of the triangles' normals from +z (triangles whose centroid is there).
struct Flatness
{
    double rms = 0, degrees = 0;
    size_t vertices = 0;
};

Flatness topFace(const TriangleMesh& m, const ParticleSet& slab)
{
    double lo[3] = {1e300, 1e300, 1e300}, hi[3] = {-1e300, -1e300, -1e300};
    for (const Vec3f& p : slab.positions)
        for (int a = 0; a < 3; ++a)
            lo[a] = std::min(lo[a], double(p[a])), hi[a] = std::max(hi[a], double(p[a]));
    const auto inside = [&](const Vec3f& p) {
        for (int a = 0; a < 2; ++a)
            if (!(p[a] > lo[a] + 0.2 * (hi[a] - lo[a]) && p[a] < hi[a] - 0.2 * (hi[a] - lo[a])))
                return false;
        return p.z > hi[2];
    };
    Flatness f;
    double sum = 0, sum2 = 0;
    for (const Vec3f& p : m.points)
        if (inside(p)) sum += p.z, sum2 += double(p.z) * p.z, ++f.vertices;
    if (f.vertices) {
        const double mean = sum / double(f.vertices);
        f.rms = std::sqrt(std::max(0.0, sum2 / double(f.vertices) - mean * mean));
    }
    double angles = 0;
    size_t triangles = 0;
    for (const auto& t : m.triangles) {
        const Vec3f a = m.points[t[0]], b = m.points[t[1]], c = m.points[t[2]];
        if (!inside((a + b + c) * (1.f / 3))) continue;
        const Vec3f u = b - a, v = c - a;
        const double nx = double(u.y) * v.z - double(u.z) * v.y,
                     ny = double(u.z) * v.x - double(u.x) * v.z,
                     nz = double(u.x) * v.y - double(u.y) * v.x;
        const double len = std::sqrt(nx * nx + ny * ny + nz * nz);
        if (!(len > 0)) continue;
        angles += std::acos(std::clamp(nz / len, -1.0, 1.0)) * 180 / M_PI, ++triangles;
    }
    f.degrees = triangles ? angles / double(triangles) : 0;
    return f;
}

/// splashsurf on `particles` (written to dir as xyz) with `options`; its OBJ read back.
TriangleMesh splashsurf(const QualityBenchOptions& o, const ParticleSet& particles, double r,
                        const std::vector<std::string>& options)
{
    const std::string in = o.dir + "/fluidsurf_quality_" + std::to_string(getpid()) + ".xyz";
    const std::string out = o.dir + "/fluidsurf_quality_" + std::to_string(getpid()) + ".obj";
    io::writeParticles(particles, in);
    std::vector<std::string> argv = {o.splashsurf, "reconstruct", in,   "-q",
                                     "-o",         out,           "-r", std::to_string(r)};
    argv.insert(argv.end(), options.begin(), options.end());
    runProcess(argv);
    TriangleMesh m = io::readMesh(out);
    std::remove(in.c_str());
    std::remove(out.c_str());
    return m;
}

const std::vector<std::string> kSplashRaw = {"-l", "2.0", "-c", "1.0", "-t", "0.6"};
const std::vector<std::string> kSplashSmooth = {"-l",
                                                "2.0",
                                                "-c",
                                                "1.0",
                                                "-t",
                                                "0.6",
                                                "--mesh-smoothing-weights=on",
                                                "--mesh-smoothing-iters=25",
                                                "--mesh-cleanup=on"};

/// Our default pipeline with the bench's field and smoothing.
ReconstructParams defaultParams(const QualityBenchOptions& o, double r)
{
    ReconstructParams p = ReconstructParams::fromRadius(r);
    p.field.field = fieldFromName(o.field);
    p.field.radiusScale = o.radiusScale;
    p.field.anisotropyRatio = o.anisotropyRatio;
    p.post.smooth = o.smooth;
    p.post.flatten = o.flatten;
    p.post.cover = o.cover;
    p.post.volume = volumeTargetFromName(o.volume);
    return p;
}

/// The same without decimation, smoothing or subdivision.
ReconstructParams rawParams(const QualityBenchOptions& o, double r)
{
    ReconstructParams p = defaultParams(o, r);
    p.post.decimate = 0, p.post.smooth = 0, p.post.subdivide = 0;
    return p;
}

} // namespace

int runQualityBench(const QualityBenchOptions& o)
{
    const bool peer = !o.splashsurf.empty();
    std::printf(
        "fluidsurf_bench quality: field %s, radius scale %g, anisotropy ratio %g, %d rounds "
        "of smoothing, flattening %s, covering %s; voxel = r, R = 4r (our defaults)%s\n\n",
        o.field.c_str(), o.radiusScale, o.anisotropyRatio, o.smooth, o.flatten ? "on" : "off",
        o.cover ? "on" : "off",
        peer ? "; splashsurf in the same run: smoothed `-l 2.0 -c 1.0 -t 0.6 "
               "--mesh-smoothing-weights=on --mesh-smoothing-iters=25 --mesh-cleanup=on`, "
               "raw `-l 2.0 -c 1.0 -t 0.6`"
             : "");
    std::printf("**Flat fluid**: `generate slab -n %zu -r %g --layers %d --jitter J --seed %llu`, "
                "the top face over the middle 60%% across: RMS of vertex heights about their mean, "
                "mean normal deviation (degrees), triangles of the whole mesh\n\n",
                o.count, o.radius, o.layers, (unsigned long long)o.seed);
    std::printf("| J | mesh | RMS height | normal deviation | triangles | RMS / splashsurf | "
                "deviation / splashsurf |\n|---|---|---|---|---|---|---|\n");
    for (const std::string& j : split(o.jitters)) {
        SceneParams sp;
        sp.count = o.count, sp.radius = o.radius, sp.layers = o.layers, sp.jitter = std::stod(j);
        sp.seed = o.seed;
        const ParticleSet slab = generateScene(Scene::Slab, sp);
        Flatness base;
        if (peer) base = topFace(splashsurf(o, slab, o.radius, kSplashSmooth), slab);
        auto row = [&](const char* name, const TriangleMesh& m) {
            const Flatness f = topFace(m, slab);
            std::printf("| %s | %s | %.2e | %.3f | %zu |", j.c_str(), name, f.rms, f.degrees,
                        m.triangles.size());
            if (peer)
                std::printf(" %.2f | %.2f |\n", f.rms / base.rms, f.degrees / base.degrees);
            else
                std::printf(" | |\n");
            std::fflush(stdout);
        };
        Context ctx;
        row("ours raw", reconstruct(slab, rawParams(o, o.radius), ctx).mesh);
        row("ours default", reconstruct(slab, defaultParams(o, o.radius), ctx).mesh);
        if (peer) row("splashsurf smoothed", splashsurf(o, slab, o.radius, kSplashSmooth));
    }
    std::printf(
        "\n**Volume**: enclosed volume / N (2r)^3; components (our droplet spheres aside); "
        "distance from the default mesh to the raw one and to today's raw SSP07 mesh (one "
        "side of the Hausdorff distance: the default mesh's farthest point), in r; centres the "
        "default mesh covered, and left outside (the library's count)\n\n");
    std::printf("| frame | N | ours raw | ours default | splashsurf raw | components raw / default "
                "| default to raw (r) | default to raw SSP07 (r) | covered / left |\n"
                "|---|---|---|---|---|---|---|---|---|\n");
    for (const Case& c : loadCases(o.scenes, o.shared)) {
        const double particleVolume = double(c.particles.size()) * std::pow(2 * c.radius, 3);
        Context ctx;
        const ReconstructResult raw = reconstruct(c.particles, rawParams(o, c.radius), ctx);
        const ReconstructResult def = reconstruct(c.particles, defaultParams(o, c.radius), ctx);
        const MeshReport rr = checkMesh(raw.mesh), dr = checkMesh(def.mesh);
        char splash[32] = "";
        if (peer)
            std::snprintf(splash, sizeof(splash), "%.3f",
                          checkMesh(splashsurf(o, c.particles, c.radius, kSplashRaw)).volume /
                              particleVolume);
        const double reach = 4 * c.radius;
        ReconstructParams ssp07 = ReconstructParams::fromRadius(c.radius);
        ssp07.post.decimate = 0, ssp07.post.smooth = 0, ssp07.post.subdivide = 0;
        const double toSsp07 =
            meshDistance(def.mesh, reconstruct(c.particles, ssp07, ctx).mesh, reach) / c.radius;
        std::printf("| %s | %zu | %.3f | %.3f | %s | %zu / %zu | %.3f | %.3f | %zu / %zu |\n",
                    c.name.c_str(), c.particles.size(), rr.volume / particleVolume,
                    dr.volume / particleVolume, splash, rr.components - raw.isolatedSpheres,
                    dr.components - def.isolatedSpheres,
                    meshDistance(def.mesh, raw.mesh, reach) / c.radius, toSsp07,
                    def.post.coveredParticles, def.post.uncoveredParticles);
        std::fflush(stdout);
    }
    return 0;
}

} // namespace bench
} // namespace fluidsurf
