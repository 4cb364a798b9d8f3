// Classify.cc - neighbour counts and color field per particle, cell by cell.
#include "classify/Classify.h"

#include "util/Lanes.h"

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace fluidsurf {
namespace classify {

namespace {
using util::kLanes;
using util::Lanes;

/// A particle closer than this many h (per axis) to the last one of its cell whose sums were
/// computed shares them (2^-12 h: 1e-3 r for h = 4r).
constexpr double kSameSpot = 1.0 / 4096;

bool sameSpot(const Vec3f& a, const Vec3f& b, float tolerance)
{
    return std::fabs(a.x - b.x) <= tolerance && std::fabs(a.y - b.y) <= tolerance &&
           std::fabs(a.z - b.z) <= tolerance;
}

struct Neighbourhood
{
    std::vector<float> x, y, z, v; // candidates of one cell, padded to a multiple of kLanes
    void clear() { x.clear(), y.clear(), z.clear(), v.clear(); }
    void pad()
    {
        while (x.size() % kLanes)
            x.push_back(3e38f), y.push_back(3e38f), z.push_back(3e38f), v.push_back(0);
    }
};
} // namespace

KernelConstants kernelConstants(const Params& params)
{
    KernelConstants k;
    k.h = params.smoothingLength;
    k.h2 = float(k.h * k.h);
    k.poly6 = 315.0 / (64.0 * M_PI * std::pow(k.h, 9));
    k.gradientScale = 6 * k.poly6 * k.h;
    k.uniformVolume = std::pow(2 * params.radius, 3);
    return k;
}

ClassRule classRule(const Params& params)
{
    const KernelConstants k = kernelConstants(params);
    ClassRule r;
    r.poly6 = k.poly6, r.gradientScale = k.gradientScale;
    r.splashNeighbours = params.splashNeighbours, r.surfaceNeighbours = params.surfaceNeighbours;
    r.colorFieldThreshold = params.colorFieldThreshold,
    r.colorGradientThreshold = params.colorGradientThreshold;
    return r;
}

Classification classifyParticles(const neighbors::CellIndex& index, const Params& params,
                                 Context& ctx, bool withNormals)
{
    const size_t n = index.size();
    Classification out;
    out.classes.assign(n, Interior);
    out.neighbours.assign(n, 0);
    out.colorField.assign(n, 0.f);
    out.colorGradient.assign(n, 0.f);
    if (withNormals) out.normals.assign(n, Vec3f(0, 0, 0));
    const KernelConstants k = kernelConstants(params);
    const ClassRule rule = classRule(params);
    const double h = k.h, uniformVolume = k.uniformVolume;
    const float h2 = k.h2;

    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, index.cellCount(), 16),
        [&](const tbb::blocked_range<size_t>& cells) {
            ctx.checkpoint();
            Neighbourhood nb;
            for (size_t c = cells.begin(); c != cells.end(); ++c) {
                const uint32_t b = index.starts[c], e = index.starts[c + 1];
                // Box of the cell's particles, widened by h: everything any of them can reach.
                // Coordinates relative to the first particle keep float rounding small.
                const Vec3f o = index.positions[b];
                double lo[3] = {o.x, o.y, o.z}, hi[3] = {o.x, o.y, o.z};
                for (uint32_t i = b; i < e; ++i)
                    for (int a = 0; a < 3; ++a) {
                        lo[a] = std::min(lo[a], double(index.positions[i][a]));
                        hi[a] = std::max(hi[a], double(index.positions[i][a]));
                    }
                for (int a = 0; a < 3; ++a)
                    lo[a] -= h, hi[a] += h;
                nb.clear();
                index.forEachCellInBox(lo, hi, [&](uint32_t cb, uint32_t ce) {
                    for (uint32_t j = cb; j < ce; ++j) {
                        const Vec3f& p = index.positions[j];
                        nb.x.push_back(float(double(p.x) - o.x));
                        nb.y.push_back(float(double(p.y) - o.y));
                        nb.z.push_back(float(double(p.z) - o.z));
                        const double rj = index.radii.empty() ? params.radius : index.radii[j];
                        nb.v.push_back(
                            float(index.radii.empty() ? uniformVolume : 8 * rj * rj * rj));
                    }
                });
                nb.pad();
                const size_t m = nb.x.size();
                uint32_t computed = b;
                for (uint32_t i = b; i < e; ++i) {
                    const Vec3f& p = index.positions[i];
                    // A particle at the spot of the last computed one has its sums: coincident
                    // particles (a degenerate frame piles 1e5 on one point, often with a little
                    // noise) cost one neighbourhood pass per spot instead of one each. No two
                    // particles of a real fluid come within kSameSpot * h of each other, so
                    // real frames are computed particle by particle as before.
                    if (i > b && sameSpot(p, index.positions[computed], float(h * kSameSpot))) {
                        out.neighbours[i] = out.neighbours[computed];
                        out.colorField[i] = out.colorField[computed];
                        out.colorGradient[i] = out.colorGradient[computed];
                        out.classes[i] = out.classes[computed];
                        if (withNormals) out.normals[i] = out.normals[computed];
                        continue;
                    }
                    computed = i;
                    const float px = float(double(p.x) - o.x), py = float(double(p.y) - o.y),
                                pz = float(double(p.z) - o.z);
                    Lanes count{}, cf{}, gx{}, gy{}, gz{};
                    for (size_t j = 0; j < m; j += kLanes) {
                        const Lanes dx = util::loadLanes(&nb.x[j]) - px,
                                    dy = util::loadLanes(&nb.y[j]) - py,
                                    dz = util::loadLanes(&nb.z[j]) - pz;
                        const Lanes d2 = dx * dx + dy * dy + dz * dz;
                        Lanes t = h2 - d2;
                        t = t > 0.f ? t : 0.f;
                        count += d2 < h2 ? Lanes{} + 1.f : Lanes{};
                        const Lanes vt2 = util::loadLanes(&nb.v[j]) * t * t;
                        cf += vt2 * t;
                        gx += vt2 * dx, gy += vt2 * dy, gz += vt2 * dz;
                    }
                    const ParticleSums ps = classifyLanes(count, cf, gx, gy, gz, rule);
                    out.neighbours[i] = ps.neighbours;
                    out.colorField[i] = ps.colorField;
                    out.colorGradient[i] = ps.gradient;
                    out.classes[i] = ps.cls;
                    if (withNormals && isSurface(ps.cls)) {
                        // The gradient's sum points into the fluid (d = x_j - x_i).
                        double g[3] = {0, 0, 0};
                        for (int l = 0; l < kLanes; ++l)
                            g[0] += gx[l], g[1] += gy[l], g[2] += gz[l];
                        const double len = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
                        if (len > 0)
                            out.normals[i] =
                                Vec3f(float(-g[0] / len), float(-g[1] / len), float(-g[2] / len));
                    }
                }
            }
        });
    for (uint8_t c : out.classes) {
        if (c == Interior)
            ++out.interior;
        else if (c == Surface)
            ++out.surface;
        else if (c == Splash)
            ++out.splash;
        else
            ++out.isolated;
    }
    return out;
}

std::vector<uint8_t> notIsolated(const Classification& c)
{
    std::vector<uint8_t> keep(c.classes.size());
    for (size_t i = 0; i < keep.size(); ++i)
        keep[i] = c.classes[i] != Isolated;
    return keep;
}

void selectClasses(Classification& c, const std::vector<uint8_t>& keep)
{
    selectInPlace(c.classes, keep);
    selectInPlace(c.neighbours, keep);
    selectInPlace(c.colorField, keep);
    selectInPlace(c.colorGradient, keep);
    selectInPlace(c.normals, keep);
}

} // namespace classify
} // namespace fluidsurf
