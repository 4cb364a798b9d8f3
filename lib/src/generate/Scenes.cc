// Scenes.cc - the generated scenes. Randomness comes from SplitMix64 rather than <random>
// distributions, whose output differs between standard libraries.
#include <fluidsurf/Error.h>
#include <fluidsurf/Scenes.h>

#include <cmath>

namespace fluidsurf {

namespace {

struct SplitMix64
{
    uint64_t state;
    uint64_t next()
    {
        uint64_t z = (state += 0x9e3779b97f4a7c15ull);
        z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ull;
        z = (z ^ (z >> 27)) * 0x94d049bb133111ebull;
        return z ^ (z >> 31);
    }
    double uniform() { return double(next() >> 11) * (1.0 / 9007199254740992.0); } // [0, 1)
};

struct Builder
{
    ParticleSet set;
    double spacing;
    void add(double x, double y, double z)
    {
        set.positions.emplace_back(float(x), float(y), float(z));
    }
};

void addBlock(Builder& b, int nx, int ny, int nz, double ox, double oy, double oz)
{
    for (int k = 0; k < nz; ++k)
        for (int j = 0; j < ny; ++j)
            for (int i = 0; i < nx; ++i)
                b.add(ox + i * b.spacing, oy + j * b.spacing, oz + k * b.spacing);
}

void addBall(Builder& b, double rho, double cx, double cy, double cz)
{
    const int m = int(std::ceil(rho));
    for (int k = -m; k <= m; ++k)
        for (int j = -m; j <= m; ++j)
            for (int i = -m; i <= m; ++i)
                if (double(i) * i + double(j) * j + double(k) * k <= rho * rho)
                    b.add(cx + i * b.spacing, cy + j * b.spacing, cz + k * b.spacing);
}

} // namespace

Scene sceneFromName(const std::string& name)
{
    if (name == "single") return Scene::Single;
    if (name == "block") return Scene::Block;
    if (name == "ball") return Scene::Ball;
    if (name == "slab") return Scene::Slab;
    if (name == "drop") return Scene::Drop;
    if (name == "sheet") return Scene::Sheet;
    if (name == "jet") return Scene::Jet;
    throw ValueError("unknown scene '" + name + "' (single, block, ball, slab, drop, sheet, jet)");
}

const char* sceneName(Scene s)
{
    switch (s) {
    case Scene::Single:
        return "single";
    case Scene::Block:
        return "block";
    case Scene::Ball:
        return "ball";
    case Scene::Slab:
        return "slab";
    case Scene::Drop:
        return "drop";
    case Scene::Sheet:
        return "sheet";
    case Scene::Jet:
        return "jet";
    }
    return "?";
}

std::vector<std::string> sceneNames()
{
    return {"single", "block", "ball", "slab", "drop", "sheet", "jet"};
}

ParticleSet generateScene(Scene scene, const SceneParams& p)
{
    if (!(p.radius > 0) || !std::isfinite(p.radius))
        throw ValueError("scene radius must be positive");
    if (p.count < 1 || p.count > (size_t(1) << 31)) throw ValueError("scene count must be 1..2^31");
    if (p.layers < 1) throw ValueError("layers must be >= 1");
    if (!(p.jitter >= 0 && p.jitter < 0.5)) throw ValueError("jitter must be in [0, 0.5) spacings");
    if ((scene == Scene::Sheet || scene == Scene::Jet) && p.layers > 64)
        throw ValueError("sheet and jet layers must be 1..64");
    if (!(p.poolDepthScale > 0)) throw ValueError("pool depth scale must be positive");
    if (!(p.poolAspect >= 1 && p.poolAspect <= 1000))
        throw ValueError("pool aspect must be in [1, 1000]");
    if (p.droplets < 0 || p.droplets > 1000) throw ValueError("droplets must be 0..1000");
    Builder b;
    b.spacing = 2.0 * p.radius;
    SplitMix64 rng{p.seed};
    const double n = double(p.count);
    b.set.positions.reserve(p.count + p.count / 4 + 16);
    switch (scene) {
    case Scene::Single:
        b.add(0, 0, 0);
        break;
    case Scene::Block: {
        const int side = std::max(1, int(std::lround(std::cbrt(n))));
        addBlock(b, side, side, side, 0, 0, 0);
        break;
    }
    case Scene::Ball:
        addBall(b, std::cbrt(3.0 * n / (4.0 * M_PI)), 0, 0, 0);
        break;
    case Scene::Slab: {
        const int side = std::max(1, int(std::lround(std::sqrt(n / p.layers))));
        for (int k = 0; k < p.layers; ++k)
            for (int j = 0; j < side; ++j)
                for (int i = 0; i < side; ++i) {
                    const double jx = (rng.uniform() * 2 - 1) * p.jitter * b.spacing;
                    const double jy = (rng.uniform() * 2 - 1) * p.jitter * b.spacing;
                    b.add(i * b.spacing + jx, j * b.spacing + jy, k * b.spacing);
                }
        break;
    }
    case Scene::Sheet: {
        // A quarter turn of a cylinder's wall about the y axis: `arc` particles around (2r apart
        // on the inner layer), `width` along y (twice as many around as along), layer k at the
        // inner radius plus k spacings. Jitter in 3D, so the sheet is not a lattice's plane.
        const int width = std::max(2, int(std::lround(std::sqrt(n / p.layers / 2))));
        const int arc = 2 * width;
        const double inner = std::max(8.0, arc / (M_PI / 2)) * b.spacing;
        auto jitter = [&] { return (rng.uniform() * 2 - 1) * p.jitter * b.spacing; };
        for (int k = 0; k < p.layers; ++k)
            for (int j = 0; j < width; ++j)
                for (int i = 0; i < arc; ++i) {
                    const double angle = i * b.spacing / inner, rho = inner + k * b.spacing;
                    const double jx = jitter(), jy = jitter(), jz = jitter();
                    b.add(rho * std::cos(angle) + jx, j * b.spacing + jy,
                          rho * std::sin(angle) + jz);
                }
        break;
    }
    case Scene::Jet: {
        // A fountain's arc z = h (1 - (x / L)^2) for x in [-L, L], h = L / 2, with slices one
        // spacing apart along it, each `layers` x `layers` particles across (in y, and in the
        // arc's normal within x-z).
        const int across = p.layers;
        const double slices = std::max(8.0, n / double(across * across));
        const double length = slices * b.spacing; // about the arc's length
        const double L = length / 2.3, h = L / 2; // an arc of this shape is about 2.3 L long
        auto jitter = [&] { return (rng.uniform() * 2 - 1) * p.jitter * b.spacing; };
        double x = -L;
        while (x <= L) {
            const double slope = -2 * h * x / (L * L), z = h * (1 - x * x / (L * L));
            const double norm = std::sqrt(1 + slope * slope);
            const double nx = -slope / norm, nz = 1 / norm; // the arc's normal in x-z
            for (int a = 0; a < across; ++a)
                for (int c = 0; c < across; ++c) {
                    const double u = (a - 0.5 * (across - 1)) * b.spacing;
                    const double v = (c - 0.5 * (across - 1)) * b.spacing;
                    const double jx = jitter(), jy = jitter(), jz = jitter();
                    b.add(x + u * nx + jx, v + jy, z + u * nz + jz);
                }
            x += b.spacing / norm; // one spacing along the arc
        }
        break;
    }
    case Scene::Drop: {
        // Pool: W x W x D with D = W / poolAspect (times the depth scale); 85% of the particles.
        // A wide pool (aspect 48) has side walls ~4% of its surface, so a deeper one adds
        // volume, not surface: what the narrow band's scaling is measured with.
        const double aspect = p.poolAspect;
        int w = std::max(4, int(std::lround(std::cbrt(0.85 * n * aspect))));
        if (w / aspect < 3)
            w = std::max(4, int(std::lround(std::sqrt(0.85 * n / 3)))); // >= 3 layers
        const int d = std::max(1, int(std::lround(std::max(3.0, w / aspect) * p.poolDepthScale)));
        addBlock(b, w, w, d, 0, 0, 0);
        // Ball above the middle of the pool, 15% of the particles, a few radii of air between.
        const double rho = std::max(1.0, std::cbrt(3.0 * 0.15 * n / (4.0 * M_PI)));
        const double c = (w - 1) * b.spacing / 2;
        const double top = (d - 1) * b.spacing;
        const double cz = top + (rho + 4) * b.spacing;
        addBall(b, rho, c, c, cz);
        // Droplets: single particles in the air beside the ball, at least 6 spacings from it
        // and 4 above the pool, so that no other particle lies within the SPH support 4r.
        for (int i = 0; i < p.droplets; ++i) {
            const double angle = 2 * M_PI * (i + rng.uniform() * 0.5) / std::max(1, p.droplets);
            const double dist = (rho + 6 + 3 * rng.uniform()) * b.spacing;
            b.add(c + dist * std::cos(angle), c + dist * std::sin(angle),
                  cz + (rng.uniform() * 2 - 1) * rho * b.spacing);
        }
        break;
    }
    }
    std::vector<int64_t> ids(b.set.size());
    for (size_t i = 0; i < ids.size(); ++i)
        ids[i] = int64_t(i);
    b.set.addInt("id", 1, std::move(ids));
    return std::move(b.set);
}

} // namespace fluidsurf
