// KernelShapes.cc - the weighted PCA of each surface particle's neighbourhood (KernelShapes.h).
#include "anisotropy/KernelShapes.h"
#include "anisotropy/SymmetricEigen.h"

#include <fluidsurf/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace fluidsurf {
namespace anisotropy {

namespace {

void validate(const ShapeParams& p)
{
    if (!(p.influenceRadius > 0) || !std::isfinite(p.influenceRadius))
        throw ValueError("anisotropic kernels: the influence radius must be positive");
    if (!(p.pcaRadius > 0) || !std::isfinite(p.pcaRadius))
        throw ValueError("anisotropic kernels: the PCA radius must be positive");
    if (!(p.maxAxisRatio >= 1 && p.maxAxisRatio <= 100))
        throw ValueError(
            "anisotropic kernels: k_r (longest over shortest axis) must be in [1, 100]");
    if (p.minNeighbours < 0 || p.minNeighbours > 10000)
        throw ValueError("anisotropic kernels: N_eps must be in [0, 10000]");
    if (!(p.sparseScale > 0 && p.sparseScale <= 4))
        throw ValueError("anisotropic kernels: k_n must be in (0, 4]");
    if (!(p.centreSmoothing >= 0 && p.centreSmoothing <= 1))
        throw ValueError("anisotropic kernels: lambda must be in [0, 1]");
}

void sphere(float* g, double radius)
{
    const float inv = float(1 / radius);
    g[0] = inv, g[1] = 0, g[2] = 0, g[3] = inv, g[4] = 0, g[5] = inv;
}

} // namespace

ShapeParams shapeParams(const Params& params)
{
    ShapeParams s;
    s.influenceRadius = params.influenceRadius;
    s.pcaRadius = params.anisotropyRadius;
    s.maxAxisRatio = params.anisotropyRatio;
    s.minNeighbours = params.anisotropyNeighbours;
    s.sparseScale = 1;
    s.centreSmoothing = params.centreSmoothing;
    return s;
}

double maxReach(const ShapeParams& p)
{
    return std::max(p.maxAxisRatio, p.sparseScale);
}

KernelShapes kernelShapes(const neighbors::CellIndex& index,
                          const classify::Classification& classes, const ShapeParams& p,
                          Context& ctx)
{
    validate(p);
    const size_t n = index.size();
    if (classes.classes.size() != n)
        throw ValueError("anisotropic kernels: the classes are not the index's");
    KernelShapes out;
    out.shapes.resize(6 * n);
    out.centres.resize(n);
    const double a = p.pcaRadius, a2 = a * a;
    std::atomic<size_t> stretched{0}, sparse{0};
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
            ctx.checkpoint();
            neighbors::NearbyCells cells(index);
            size_t myStretched = 0, mySparse = 0;
            for (size_t i = r.begin(); i != r.end(); ++i) {
                float* const g = &out.shapes[6 * i];
                const Vec3f xi = index.positions[i];
                out.centres[i] = xi;
                if (!classify::isSurface(classes.classes[i])) {
                    sphere(g, p.influenceRadius);
                    continue;
                }
                // the weighted mean and spread about x_i first (one pass), shifted to the mean
                // after: sum w (x_j - m)(x_j - m)^T = sum w d d^T - W (m - x_i)(m - x_i)^T, d = x_j
                // - x_i
                double w = 0, d[3] = {0, 0, 0}, dd[6] = {0, 0, 0, 0, 0, 0};
                int neighbours = -1; // self aside
                const double lo[3] = {xi.x - a, xi.y - a, xi.z - a},
                             hi[3] = {xi.x + a, xi.y + a, xi.z + a};
                cells.forEachCellInBox(lo, hi, [&](uint32_t begin, uint32_t end) {
                    for (uint32_t j = begin; j < end; ++j) {
                        const double ex = double(index.positions[j].x) - xi.x,
                                     ey = double(index.positions[j].y) - xi.y,
                                     ez = double(index.positions[j].z) - xi.z;
                        const double s2 = (ex * ex + ey * ey + ez * ez) / a2;
                        if (!(s2 < 1)) continue;
                        const double wj = 1 - s2 * std::sqrt(s2);
                        ++neighbours;
                        w += wj;
                        d[0] += wj * ex, d[1] += wj * ey, d[2] += wj * ez;
                        dd[0] += wj * ex * ex, dd[1] += wj * ex * ey, dd[2] += wj * ex * ez;
                        dd[3] += wj * ey * ey, dd[4] += wj * ey * ez, dd[5] += wj * ez * ez;
                    }
                });
                if (neighbours < p.minNeighbours || !(w > 0)) {
                    sphere(g, p.sparseScale * p.influenceRadius);
                    ++mySparse;
                    continue;
                }
                const double m[3] = {d[0] / w, d[1] / w, d[2] / w}; // the mean, from x_i
                const double c[6] = {dd[0] / w - m[0] * m[0], dd[1] / w - m[0] * m[1],
                                     dd[2] / w - m[0] * m[2], dd[3] / w - m[1] * m[1],
                                     dd[4] / w - m[1] * m[2], dd[5] / w - m[2] * m[2]};
                const Eigen3 e = symmetricEigen(c);
                const double s1 = std::max(e.values[0], 1e-300);
                double t[3];
                for (int k = 0; k < 3; ++k)
                    t[k] = std::max(e.values[k], s1 / p.maxAxisRatio);
                const double scale = p.influenceRadius / t[2]; // the shortest axis: R
                double inv[3];
                for (int k = 0; k < 3; ++k)
                    inv[k] = 1 / (scale * t[k]);
                // G = sum_k inv_k v_k v_k^T
                const int row[6] = {0, 0, 0, 1, 1, 2}, col[6] = {0, 1, 2, 1, 2, 2};
                for (int q = 0; q < 6; ++q) {
                    double sum = 0;
                    for (int k = 0; k < 3; ++k)
                        sum += inv[k] * e.vectors[k][row[q]] * e.vectors[k][col[q]];
                    g[q] = float(sum);
                }
                const double lambda = p.centreSmoothing;
                out.centres[i] = Vec3f(float(xi.x + lambda * m[0]), float(xi.y + lambda * m[1]),
                                       float(xi.z + lambda * m[2]));
                ++myStretched;
            }
            stretched += myStretched, sparse += mySparse;
        });
    out.stretched = stretched, out.sparse = sparse;
    return out;
}

KernelParticles kernelParticles(const neighbors::CellIndex& index,
                                const classify::Classification& classes, const KernelShapes& shapes,
                                bool keepIsolated, double cellSize, Context& ctx)
{
    const size_t n = index.size();
    std::vector<Vec3f> centres;
    std::vector<float> radii, kept;
    centres.reserve(n), kept.reserve(6 * n);
    for (size_t i = 0; i < n; ++i) {
        if (!keepIsolated && classes.classes[i] == classify::Isolated) continue;
        centres.push_back(shapes.centres[i]);
        if (!index.radii.empty()) radii.push_back(index.radii[i]);
        kept.insert(kept.end(), &shapes.shapes[6 * i], &shapes.shapes[6 * i] + 6);
    }
    KernelParticles out;
    out.centres = neighbors::buildCellIndex(centres.data(), radii.empty() ? nullptr : radii.data(),
                                            centres.size(), cellSize, ctx);
    out.shapes.resize(kept.size());
    for (size_t k = 0; k < centres.size(); ++k)
        std::copy_n(&kept[6 * size_t(out.centres.order[k])], 6, &out.shapes[6 * k]);
    return out;
}

} // namespace anisotropy
} // namespace fluidsurf
