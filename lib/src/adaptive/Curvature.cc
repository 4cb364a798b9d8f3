// Curvature.cc - kappa of the surface particles from their color-field normals.
#include "adaptive/Curvature.h"

#include "util/Vec3d.h"

#include <fluidsurf/Error.h>

#include <tbb/parallel_for.h>

#include <cmath>

namespace fluidsurf {
namespace adaptive {

namespace {

/// Calls f(j, d2) for every particle j != i closer than h to particle i.
template <typename F>
void forEachNeighbour(const neighbors::CellIndex& index, size_t i, double h, F&& f)
{
    const Vec3f& p = index.positions[i];
    const double lo[3] = {p.x - h, p.y - h, p.z - h}, hi[3] = {p.x + h, p.y + h, p.z + h};
    const double h2 = h * h;
    index.forEachCellInBox(lo, hi, [&](uint32_t begin, uint32_t end) {
        for (uint32_t j = begin; j < end; ++j) {
            if (j == i) continue;
            const Vec3f& q = index.positions[j];
            const double dx = double(p.x) - q.x, dy = double(p.y) - q.y, dz = double(p.z) - q.z;
            const double d2 = dx * dx + dy * dy + dz * dz;
            if (d2 < h2) f(j, d2, dx, dy, dz);
        }
    });
}

} // namespace

std::vector<float> particleCurvature(const neighbors::CellIndex& index,
                                     const classify::Classification& classes, const Params& params,
                                     Context& ctx)
{
    const size_t n = index.size();
    const double h = params.smoothingLength;
    const auto& cls = classes.classes;
    if (classes.normals.size() != n)
        throw Error("particleCurvature: the classification has no normals");
    const std::vector<Vec3f>& normal = classes.normals;
    std::vector<float> kappa(n, 0.f);
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
            ctx.checkpoint();
            for (size_t i = r.begin(); i != r.end(); ++i) {
                if (!classify::isSurface(cls[i])) continue;
                double k = 0;
                forEachNeighbour(index, i, h, [&](uint32_t j, double d2, double, double, double) {
                    if (!classify::isSurface(cls[j])) return;
                    k += (1 - toVec3d(normal[i]).dot(toVec3d(normal[j]))) * (1 - std::sqrt(d2) / h);
                });
                kappa[i] = float(k);
            }
        });
    return kappa;
}

} // namespace adaptive
} // namespace fluidsurf
