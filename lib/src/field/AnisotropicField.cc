// AnisotropicField.cc - the anisotropic SSP07 field, a scalar gather per leaf (see the header).
#include "field/AnisotropicField.h"

#include "field/FieldValue.h"

#include <openvdb/tree/LeafManager.h>

#include <tbb/parallel_for.h>

#include <atomic>
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
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(tree);
    std::atomic<size_t> evaluations{0};
    tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.leafCount(), 4), [&](const auto& r) {
        ctx.checkpoint();
        neighbors::NearbyCells cells(centres);
        std::vector<uint32_t> near;
        size_t mine = 0;
        for (size_t l = r.begin(); l != r.end(); ++l) {
            auto& leaf = leaves.leaf(l);
            const openvdb::Coord o = leaf.origin();
            double lo[3], hi[3];
            for (int a = 0; a < 3; ++a)
                lo[a] = o[a] * dx - reach, hi[a] = (o[a] + 7) * dx + reach;
            near.clear();
            cells.forEachCellInBox(lo, hi, [&](uint32_t b, uint32_t e) {
                for (uint32_t j = b; j < e; ++j)
                    near.push_back(j);
            });
            for (auto v = leaf.beginValueOn(); v; ++v) {
                const openvdb::Coord c = v.getCoord();
                const double x[3] = {c.x() * dx, c.y() * dx, c.z() * dx};
                FieldSums s;
                for (uint32_t j : near) {
                    const Vec3f& p = centres.positions[j];
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
