// ScatterField.cc - serial scatter into dense accumulators.
#include "field/ScatterField.h"

#include "field/FieldValue.h"
#include "narrowband/NarrowBand.h"

#include <cmath>
#include <vector>

namespace fluidsurf {
namespace field {

namespace {
struct Acc  // float sums per vertex, as the gather keeps them per lane
{
    float w, d[3], r, g[3], m[6];
};
} // namespace

openvdb::FloatTree::Ptr scatterField(const neighbors::CellIndex& particles, const Params& params, size_t* evaluations)
{
    const bool radii = !particles.radii.empty();
    const FieldConstants constants = FieldConstants::from(params, radii);
    auto tree = std::make_shared<openvdb::FloatTree>(constants.background);
    const openvdb::CoordBBox box = narrowband::boundingVolume(particles, params);
    if (box.empty()) return tree;
    narrowband::checkDenseMemory(box, sizeof(Acc), "the scatter baseline");
    const openvdb::Coord lo = box.min(), dim = box.dim();
    const size_t nx = dim.x(), ny = dim.y(), nz = dim.z();
    std::vector<Acc> acc(nx * ny * nz, Acc{});
    const double dx = params.voxelSize, R = params.influenceRadius;
    const float invR2 = float(1 / (R * R));
    const bool ssp07 = constants.ssp07;

    for (size_t p = 0; p < particles.size(); ++p) {
        const Vec3f& x = particles.positions[p];
        int a0[3], a1[3];
        for (int a = 0; a < 3; ++a) {
            a0[a] = int(std::ceil((x[a] - R) / dx));
            a1[a] = int(std::floor((x[a] + R) / dx));
        }
        const float rp = radii ? particles.radii[p] : 0.f;
        for (int i = a0[0]; i <= a1[0]; ++i)
            for (int j = a0[1]; j <= a1[1]; ++j)
                for (int k = a0[2]; k <= a1[2]; ++k) {
                    const float ex = float(x.x - i * dx), ey = float(x.y - j * dx), ez = float(x.z - k * dx);
                    const float s2 = (ex * ex + ey * ey + ez * ez) * invR2;
                    if (!(s2 < 1.f)) continue;
                    const float t = 1.f - s2, t2 = t * t, wt = t2 * t;
                    Acc& v = acc[(size_t(i - lo.x()) * ny + size_t(j - lo.y())) * nz + size_t(k - lo.z())];
                    v.w += wt;
                    v.d[0] += wt * ex, v.d[1] += wt * ey, v.d[2] += wt * ez;
                    v.r += wt * rp;
                    if (ssp07) {
                        const float gx = t2 * ex, gy = t2 * ey, gz = t2 * ez;
                        v.g[0] += gx, v.g[1] += gy, v.g[2] += gz;
                        v.m[0] += gx * ex, v.m[1] += gx * ey, v.m[2] += gx * ez;
                        v.m[3] += gy * ey, v.m[4] += gy * ez, v.m[5] += gz * ez;
                    }
                }
    }
    openvdb::tree::ValueAccessor<openvdb::FloatTree> out(*tree);
    size_t n = 0;
    for (size_t i = 0; i < nx; ++i)
        for (size_t j = 0; j < ny; ++j)
            for (size_t k = 0; k < nz; ++k) {
                const Acc& v = acc[(i * ny + j) * nz + k];
                FieldSums s;
                s.w = v.w, s.r = v.r;
                for (int a = 0; a < 3; ++a) s.d[a] = v.d[a], s.g[a] = v.g[a];
                for (int a = 0; a < 6; ++a) s.m[a] = v.m[a];
                const float phi = fieldValue(s, constants);
                ++n;
                if (std::abs(phi) < constants.background)
                    out.setValue(openvdb::Coord(int(i) + lo.x(), int(j) + lo.y(), int(k) + lo.z()), phi);
            }
    if (evaluations) *evaluations = n;
    return tree;
}

} // namespace field
} // namespace fluidsurf
