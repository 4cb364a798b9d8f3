// AnisotropicField.cc - the anisotropic SSP07 field, a scalar gather per leaf (see the header).
#include "field/AnisotropicField.h"

#include "field/FieldValue.h"

#include <openvdb/tree/LeafManager.h>

#include <tbb/parallel_for.h>

#include <atomic>
#include <climits>
#include <cmath>
#include <vector>

namespace fluidsurf {
namespace field {

size_t evaluateAnisotropicField(openvdb::FloatTree& tree, const neighbors::CellIndex& centres,
                                const float* shapes, double reach, const Params& params,
                                const Level& level, Context& ctx)
{
    const bool radii = !centres.radii.empty();
    const FieldConstants constants = fieldConstants(params, level, radii);
    const double dx = level.voxelSize, R2 = params.influenceRadius * params.influenceRadius;
    // Each kernel's bounding box, half extents sqrt((G^-2)_aa) (a little wider against rounding):
    // a voxel reads only the kernels whose boxes hold it, in the same order, so culling by box
    // changes no bit (a kernel outside its box adds exactly nothing). The leaf's gather reaches as
    // far as the longest kernel; a voxel's column keeps about a tenth of what the leaf gathers.
    const size_t n = centres.size();
    std::vector<float> extent(3 * n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const auto& r) {
        for (size_t j = r.begin(); j != r.end(); ++j) {
            const float* g = shapes + 6 * j;
            const double m[3][3] = {{g[0], g[1], g[2]}, {g[1], g[3], g[4]}, {g[2], g[4], g[5]}};
            const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                               m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
            for (int a = 0; a < 3; ++a) {
                double sum = 0; // row a of G^-1 (the adjugate over det), squared
                for (int b = 0; b < 3; ++b) {
                    const int a1 = (b + 1) % 3, a2 = (b + 2) % 3, b1 = (a + 1) % 3,
                              b2 = (a + 2) % 3;
                    const double inv = (m[a1][b1] * m[a2][b2] - m[a1][b2] * m[a2][b1]) / det;
                    sum += inv * inv;
                }
                extent[3 * j + a] = float(std::sqrt(sum) * 1.001 + 1e-6 * reach);
            }
        }
    });
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(tree);
    std::atomic<size_t> evaluations{0};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.leafCount(), 4), [&](const auto& r) {
        ctx.checkpoint();
        neighbors::NearbyCells cells(centres);
        std::vector<uint32_t> near, column;
        size_t mine = 0;
        for (size_t l = r.begin(); l != r.end(); ++l) {
            auto& leaf = leaves.leaf(l);
            const openvdb::Coord o = leaf.origin();
            double lo[3], hi[3];
            for (int a = 0; a < 3; ++a)
                lo[a] = o[a] * dx - reach, hi[a] = (o[a] + 7) * dx + reach;
            near.clear();
            cells.forEachCellInBox(lo, hi, [&](uint32_t b, uint32_t e) {
                for (uint32_t j = b; j < e; ++j) {
                    const Vec3f& p = centres.positions[j];
                    const float* ext = &extent[3 * size_t(j)];
                    bool overlaps = true;
                    for (int a = 0; a < 3; ++a)
                        overlaps &=
                            p[a] + ext[a] >= lo[a] + reach && p[a] - ext[a] <= hi[a] - reach;
                    if (overlaps) near.push_back(j);
                }
            });
            int columnX = INT32_MIN, columnY = INT32_MIN;
            for (auto v = leaf.beginValueOn(); v; ++v) {
                const openvdb::Coord c = v.getCoord();
                const double x[3] = {c.x() * dx, c.y() * dx, c.z() * dx};
                if (c.x() != columnX || c.y() != columnY) { // the kernels over this (x, y)
                    columnX = c.x(), columnY = c.y();
                    column.clear();
                    for (uint32_t j : near) {
                        const Vec3f& p = centres.positions[j];
                        const float* ext = &extent[3 * size_t(j)];
                        if (std::fabs(p.x - x[0]) <= ext[0] && std::fabs(p.y - x[1]) <= ext[1])
                            column.push_back(j);
                    }
                }
                FieldSums s;
                for (uint32_t j : column) {
                    const Vec3f& p = centres.positions[j];
                    if (!(std::fabs(p.z - x[2]) <= extent[3 * size_t(j) + 2])) continue;
                    const double d[3] = {p.x - x[0], p.y - x[1], p.z - x[2]};
                    const float* g = shapes + 6 * size_t(j);
                    const double u[3] = {g[0] * d[0] + g[1] * d[1] + g[2] * d[2],
                                         g[1] * d[0] + g[3] * d[1] + g[4] * d[2],
                                         g[2] * d[0] + g[4] * d[1] + g[5] * d[2]};
                    const double t = 1 - (u[0] * u[0] + u[1] * u[1] + u[2] * u[2]);
                    if (!(t > 1e-6)) continue;
                    const double t2 = t * t, w = t2 * t;
                    s.w += w;
                    for (int a = 0; a < 3; ++a)
                        s.d[a] += w * d[a];
                    if (radii) s.r += w * centres.radii[j];
                    // A d = G (G d) = G u, scaled by R^2 so that a sphere gives A' = I (FieldMath
                    // multiplies by 6 / R^2)
                    const double ad[3] = {R2 * (g[0] * u[0] + g[1] * u[1] + g[2] * u[2]),
                                          R2 * (g[1] * u[0] + g[3] * u[1] + g[4] * u[2]),
                                          R2 * (g[2] * u[0] + g[4] * u[1] + g[5] * u[2])};
                    for (int a = 0; a < 3; ++a)
                        s.g[a] += t2 * ad[a];
                    // the symmetric part of d (A d)^T
                    s.m[0] += t2 * d[0] * ad[0];
                    s.m[1] += t2 * 0.5 * (d[0] * ad[1] + d[1] * ad[0]);
                    s.m[2] += t2 * 0.5 * (d[0] * ad[2] + d[2] * ad[0]);
                    s.m[3] += t2 * d[1] * ad[1];
                    s.m[4] += t2 * 0.5 * (d[1] * ad[2] + d[2] * ad[1]);
                    s.m[5] += t2 * d[2] * ad[2];
                }
                v.setValue(fieldValue(s, constants));
                ++mine;
            }
        }
        evaluations += mine;
    });
    return evaluations;
}

} // namespace field
} // namespace fluidsurf
