// ScatterField.cc - serial scatter into dense accumulators.
#include "field/ScatterField.h"

#include "field/FieldValue.h"
#include "narrowband/NarrowBand.h"

#include <cmath>
#include <vector>

namespace fluidsurf {
namespace field {

namespace {
/// Every particle adds itself to every vertex within R of it, in particle order.
template <bool Ssp07, bool Radii>
void scatter(const neighbors::CellIndex& particles, const openvdb::CoordBBox& box, double dx,
             double R, std::vector<PartialSums<float>>& acc, Context& ctx)
{
    const openvdb::Coord lo = box.min(), dim = box.dim();
    const size_t ny = dim.y(), nz = dim.z();
    const float invR2 = float(1 / (R * R));
    for (size_t p = 0; p < particles.size(); ++p) {
        if (p % 4096 == 0) ctx.checkpoint();
        const Vec3f& x = particles.positions[p];
        int a0[3], a1[3];
        for (int a = 0; a < 3; ++a) {
            a0[a] = int(std::ceil((x[a] - R) / dx));
            a1[a] = int(std::floor((x[a] + R) / dx));
        }
        const float rp = Radii ? particles.radii[p] : 0.f;
        for (int i = a0[0]; i <= a1[0]; ++i)
            for (int j = a0[1]; j <= a1[1]; ++j)
                for (int k = a0[2]; k <= a1[2]; ++k) {
                    const float ex = float(x.x - i * dx), ey = float(x.y - j * dx),
                                ez = float(x.z - k * dx);
                    const float s2 = (ex * ex + ey * ey + ez * ez) * invR2;
                    if (!(s2 < 1.f)) continue; // adds zero; skipping it is what makes scatter fast
                    addParticle<Ssp07, Radii>(
                        acc[(size_t(i - lo.x()) * ny + size_t(j - lo.y())) * nz +
                            size_t(k - lo.z())],
                        ex, ey, ez, s2, rp);
                }
    }
}
} // namespace

openvdb::FloatTree::Ptr scatterField(const neighbors::CellIndex& particles, const Params& params,
                                     const Level& level, Context& ctx, size_t* evaluations)
{
    const bool radii = !particles.radii.empty();
    const FieldConstants constants = fieldConstants(params, level, radii);
    auto tree = std::make_shared<openvdb::FloatTree>(constants.background);
    const openvdb::CoordBBox box = narrowband::boundingVolume(particles, params, level);
    if (box.empty()) return tree;
    narrowband::checkDenseMemory(box, sizeof(PartialSums<float>), "the scatter baseline");
    const openvdb::Coord lo = box.min(), dim = box.dim();
    const size_t nx = dim.x(), ny = dim.y(), nz = dim.z();
    std::vector<PartialSums<float>> acc(nx * ny * nz);
    const double dx = level.voxelSize, R = params.influenceRadius;
    if (constants.ssp07)
        radii ? scatter<true, true>(particles, box, dx, R, acc, ctx)
              : scatter<true, false>(particles, box, dx, R, acc, ctx);
    else
        radii ? scatter<false, true>(particles, box, dx, R, acc, ctx)
              : scatter<false, false>(particles, box, dx, R, acc, ctx);

    openvdb::tree::ValueAccessor<openvdb::FloatTree> out(*tree);
    for (size_t i = 0; i < nx; ++i)
        for (size_t j = 0; j < ny; ++j)
            for (size_t k = 0; k < nz; ++k) {
                const float phi = fieldValue(toFieldSums(acc[(i * ny + j) * nz + k]), constants);
                if (std::abs(phi) < constants.background)
                    out.setValue(openvdb::Coord(int(i) + lo.x(), int(j) + lo.y(), int(k) + lo.z()),
                                 phi);
            }
    if (evaluations) *evaluations = nx * ny * nz;
    return tree;
}

} // namespace field
} // namespace fluidsurf
