// KernelShapes.cc - the weighted PCA of each surface particle's neighbourhood (KernelShapes.h).
#include "anisotropy/KernelShapes.h"
#include "anisotropy/SymmetricEigen.h"

// Moments in 8-float registers, inside functions compiled for AVX2 only.
#pragma GCC diagnostic ignored "-Wpsabi"

#include "util/Lanes.h"
#include "util/Points4.h"

#include <fluidsurf/Error.h>

#include <immintrin.h>

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

/// A particle's weighted moments about x_i: the weights' sum, the first and second moments of the
/// offsets d = x_j - x_i over its neighbours within a (weights 1 - (|d| / a)^3), and how many they
/// are (self included).
struct Moments
{
    double w = 0, d[3] = {0, 0, 0}, dd[6] = {0, 0, 0, 0, 0, 0};
    int count = 0;
};

/// One neighbourhood's moments in double, one particle at a time (CPUs without AVX2).
template <typename Cells>
Moments momentsNarrow(const neighbors::CellIndex& index, Cells& cells, Vec3f xi, double a)
{
    Moments m;
    const double a2 = a * a;
    const double lo[3] = {xi.x - a, xi.y - a, xi.z - a}, hi[3] = {xi.x + a, xi.y + a, xi.z + a};
    cells.forEachCellInBox(lo, hi, [&](uint32_t begin, uint32_t end) {
        for (uint32_t j = begin; j < end; ++j) {
            const double ex = double(index.positions[j].x) - xi.x,
                         ey = double(index.positions[j].y) - xi.y,
                         ez = double(index.positions[j].z) - xi.z;
            const double s2 = (ex * ex + ey * ey + ez * ez) / a2;
            if (!(s2 < 1)) continue;
            const double wj = 1 - s2 * std::sqrt(s2);
            ++m.count;
            m.w += wj;
            m.d[0] += wj * ex, m.d[1] += wj * ey, m.d[2] += wj * ez;
            m.dd[0] += wj * ex * ex, m.dd[1] += wj * ex * ey, m.dd[2] += wj * ex * ez;
            m.dd[3] += wj * ey * ey, m.dd[4] += wj * ey * ez, m.dd[5] += wj * ez * ez;
        }
    });
    return m;
}

using util::WideLanes;

/// The lanes of v added in a fixed order, in double.
inline double sumOfLanes(const WideLanes& v)
{
    return ((double(v[0]) + v[1]) + (double(v[2]) + v[3])) +
           ((double(v[4]) + v[5]) + (double(v[6]) + v[7]));
}

/// momentsNarrow eight neighbours a register with AVX2, in float: the offsets of two floats
/// within 2a of each other are exact or nearly (Sterbenz), and a neighbourhood's ~270 terms make
/// 35 a lane. Most of the kernel-shape stage's time went to the one-at-a-time loop (0.75 s of
/// 1.34 s on the 1.7M-particle frame, 2 cores).
/// (The cells' ranges come in a list, not through a callback: a lambda here would be compiled
/// without AVX.)
__attribute__((target("avx2,fma"))) Moments momentsWide(const neighbors::CellIndex& index,
                                                        const std::vector<uint64_t>& ranges,
                                                        Vec3f xi, double a)
{
    const float invA2 = float(1 / (a * a));
    WideLanes w{}, d0{}, d1{}, d2{}, xx{}, xy{}, xz{}, yy{}, yz{}, zz{};
    int count = 0;
    for (const uint64_t range : ranges) {
        const uint32_t begin = uint32_t(range), end = uint32_t(range >> 32);
        for (uint32_t j = begin; j < end; j += 8) {
            Vec3f tail[8]; // the last ones, padded with points far away
            const Vec3f* p = &index.positions[j];
            if (end - j < 8) {
                for (uint32_t k = 0; k < 8; ++k)
                    tail[k] = j + k < end ? index.positions[j + k] : Vec3f(1e30f, 1e30f, 1e30f);
                p = tail;
            }
            __m128 x0, y0, z0, x1, y1, z1;
            util::splitPoints4(p, x0, y0, z0);
            util::splitPoints4(p + 4, x1, y1, z1);
            const WideLanes ex = WideLanes(_mm256_set_m128(x1, x0)) - xi.x,
                            ey = WideLanes(_mm256_set_m128(y1, y0)) - xi.y,
                            ez = WideLanes(_mm256_set_m128(z1, z0)) - xi.z;
            const WideLanes s2 = (ex * ex + ey * ey + ez * ez) * invA2;
            const auto in = s2 < 1.f;
            const WideLanes root = WideLanes(_mm256_sqrt_ps(__m256(s2)));
            const WideLanes wj = in ? 1.f - s2 * root : WideLanes{};
            count += __builtin_popcount(unsigned(_mm256_movemask_ps(__m256(in))));
            w += wj;
            const WideLanes wx = wj * ex, wy = wj * ey, wz = wj * ez;
            d0 += wx, d1 += wy, d2 += wz;
            xx += wx * ex, xy += wx * ey, xz += wx * ez;
            yy += wy * ey, yz += wy * ez, zz += wz * ez;
        }
    }
    Moments m;
    m.count = count;
    m.w = sumOfLanes(w);
    m.d[0] = sumOfLanes(d0), m.d[1] = sumOfLanes(d1), m.d[2] = sumOfLanes(d2);
    m.dd[0] = sumOfLanes(xx), m.dd[1] = sumOfLanes(xy), m.dd[2] = sumOfLanes(xz);
    m.dd[3] = sumOfLanes(yy), m.dd[4] = sumOfLanes(yz), m.dd[5] = sumOfLanes(zz);
    return m;
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
    const double a = p.pcaRadius;
    const bool wide = util::doubleRegisterLanes() == 4 && __builtin_cpu_supports("fma");
    std::atomic<size_t> stretched{0}, sparse{0};
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, n, 1024), [&](const tbb::blocked_range<size_t>& r) {
            ctx.checkpoint();
            neighbors::NearbyCells cells(index);
            std::vector<uint64_t> ranges;
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
                Moments mo;
                if (wide) {
                    const double lo[3] = {xi.x - a, xi.y - a, xi.z - a},
                                 hi[3] = {xi.x + a, xi.y + a, xi.z + a};
                    ranges.clear();
                    cells.forEachCellInBox(lo, hi, [&](uint32_t b, uint32_t e) {
                        ranges.push_back(uint64_t(e) << 32 | b);
                    });
                    mo = momentsWide(index, ranges, xi, a);
                } else {
                    mo = momentsNarrow(index, cells, xi, a);
                }
                const double w = mo.w, *d = mo.d, *dd = mo.dd;
                const int neighbours = mo.count - 1; // self aside
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

KernelParticles kernelParticles(neighbors::CellIndex&& index,
                                const classify::Classification& classes, const KernelShapes& shapes,
                                bool keepIsolated)
{
    KernelParticles out;
    const size_t n = index.size();
    if (keepIsolated || classes.isolated == 0) {
        out.shapes = shapes.shapes;
    } else {
        const std::vector<uint8_t> keep = classify::notIsolated(classes);
        out.shapes.resize(6 * (n - classes.isolated));
        size_t k = 0;
        for (size_t i = 0; i < n; ++i)
            if (keep[i]) std::copy_n(&shapes.shapes[6 * i], 6, &out.shapes[6 * k++]);
        neighbors::keepParticles(index, keep);
    }
    out.centres = std::move(index);
    return out;
}

} // namespace anisotropy
} // namespace fluidsurf
