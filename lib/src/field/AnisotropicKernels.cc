// AnisotropicKernels.cc - what the anisotropic gather needs of each kernel, made once a frame
// (AnisotropicField.h): A' = R^2 G^2, the box of its support, a bound on its stretch and, for
// yt10, its density factor.
#include "field/AnisotropicField.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace fluidsurf {
namespace field {

AnisotropicKernels anisotropicKernels(const neighbors::CellIndex& centres, const float* shapes,
                                      double reach, const Params& params)
{
    const size_t n = centres.size();
    const double R = params.influenceRadius;
    AnisotropicKernels t;
    t.centres = &centres, t.reach = reach;
    t.a.resize(6 * n), t.extent.resize(3 * n), t.stretch.resize(n);
    const bool density = params.field == FieldKind::Yt10;
    if (density) t.weight.resize(n);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 4096), [&](const auto& r) {
        for (size_t j = r.begin(); j != r.end(); ++j) {
            const float* g = shapes + 6 * j;
            const double m[3][3] = {{g[0], g[1], g[2]}, {g[1], g[3], g[4]}, {g[2], g[4], g[5]}};
            double a[3][3];
            for (int p = 0; p < 3; ++p)
                for (int q = 0; q < 3; ++q)
                    a[p][q] = R * R * (m[p][0] * m[0][q] + m[p][1] * m[1][q] + m[p][2] * m[2][q]);
            const int upper[6][2] = {{0, 0}, {0, 1}, {0, 2}, {1, 1}, {1, 2}, {2, 2}};
            for (int k = 0; k < 6; ++k)
                t.a[6 * j + k] = float(a[upper[k][0]][upper[k][1]]);
            double lambda = 0; // Gershgorin: no eigenvalue above the largest row sum
            for (int p = 0; p < 3; ++p)
                lambda =
                    std::max(lambda, std::fabs(a[p][0]) + std::fabs(a[p][1]) + std::fabs(a[p][2]));
            t.stretch[j] = float(std::sqrt(lambda) * 1.0001);
            if (density) {
                const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                                   m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                                   m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
                const double r = centres.radii.empty() ? params.radius : centres.radii[j];
                t.weight[j] = float(8 * r * r * r * 315 / (64 * M_PI) * det);
            }
            const double det = m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) -
                               m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
                               m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0]);
            for (int p = 0; p < 3; ++p) {
                double sum = 0; // row p of G^-1 (the adjugate over det), squared
                for (int q = 0; q < 3; ++q) {
                    const int p1 = (q + 1) % 3, p2 = (q + 2) % 3, q1 = (p + 1) % 3,
                              q2 = (p + 2) % 3;
                    const double inv = (m[p1][q1] * m[p2][q2] - m[p1][q2] * m[p2][q1]) / det;
                    sum += inv * inv;
                }
                t.extent[3 * j + p] = float(std::sqrt(sum) * 1.001 + 1e-6 * reach);
            }
        }
    });
    return t;
}

} // namespace field
} // namespace fluidsurf
