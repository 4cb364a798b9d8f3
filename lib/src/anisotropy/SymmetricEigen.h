// SymmetricEigen.h - all eigenvalues and eigenvectors of a symmetric 3x3 matrix, by cyclic
// Jacobi rotations in double: slower than the closed form FieldMath.h uses for the largest
// eigenvalue alone, but its vectors stay orthonormal when two eigenvalues meet (a particle on
// a flat face has two equal tangential variances), and it runs the same steps on the host and
// the device (FLUIDSURF_HD).
#pragma once

#include "util/HostDevice.h"

#include <math.h>

namespace fluidsurf {
namespace anisotropy {

/// values descending; vectors[k] the unit eigenvector of values[k] (a right-handed frame).
struct Eigen3
{
    double values[3];
    double vectors[3][3];
};

/// a: (xx, xy, xz, yy, yz, zz). Sweeps until the off-diagonal part is below 1e-15 of the
/// matrix's size (at most 16 sweeps; three or four are usual).
FLUIDSURF_HD inline Eigen3 symmetricEigen(const double a[6])
{
    double m[3][3] = {{a[0], a[1], a[2]}, {a[1], a[3], a[4]}, {a[2], a[4], a[5]}};
    double v[3][3] = {{1, 0, 0}, {0, 1, 0}, {0, 0, 1}}; // columns: the eigenvectors
    const double size = fabs(a[0]) + fabs(a[3]) + fabs(a[5]) + fabs(a[1]) + fabs(a[2]) + fabs(a[4]);
    for (int sweep = 0; sweep < 16; ++sweep) {
        const double off = fabs(m[0][1]) + fabs(m[0][2]) + fabs(m[1][2]);
        if (!(off > 1e-15 * size)) break; // (also 0 / NaN: nothing to rotate)
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (m[p][q] == 0) continue;
                // the rotation that zeroes m[p][q] (Numerical Recipes' stable form)
                const double theta = (m[q][q] - m[p][p]) / (2 * m[p][q]);
                const double t = (theta >= 0 ? 1 : -1) / (fabs(theta) + sqrt(theta * theta + 1));
                const double c = 1 / sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < 3; ++k) { // m = m J
                    const double mkp = m[k][p], mkq = m[k][q];
                    m[k][p] = c * mkp - s * mkq, m[k][q] = s * mkp + c * mkq;
                }
                for (int k = 0; k < 3; ++k) { // m = J^T m
                    const double mpk = m[p][k], mqk = m[q][k];
                    m[p][k] = c * mpk - s * mqk, m[q][k] = s * mpk + c * mqk;
                }
                for (int k = 0; k < 3; ++k) { // v = v J
                    const double vkp = v[k][p], vkq = v[k][q];
                    v[k][p] = c * vkp - s * vkq, v[k][q] = s * vkp + c * vkq;
                }
            }
    }
    // descending, by a fixed three-comparison sort
    int order[3] = {0, 1, 2};
    for (int i = 0; i < 2; ++i)
        for (int j = 0; j < 2 - i; ++j)
            if (m[order[j]][order[j]] < m[order[j + 1]][order[j + 1]]) {
                const int swap = order[j];
                order[j] = order[j + 1], order[j + 1] = swap;
            }
    Eigen3 e;
    for (int k = 0; k < 3; ++k) {
        e.values[k] = m[order[k]][order[k]];
        for (int i = 0; i < 3; ++i)
            e.vectors[k][i] = v[i][order[k]];
    }
    // right-handed: the third vector the cross product of the first two
    e.vectors[2][0] = e.vectors[0][1] * e.vectors[1][2] - e.vectors[0][2] * e.vectors[1][1];
    e.vectors[2][1] = e.vectors[0][2] * e.vectors[1][0] - e.vectors[0][0] * e.vectors[1][2];
    e.vectors[2][2] = e.vectors[0][0] * e.vectors[1][1] - e.vectors[0][1] * e.vectors[1][0];
    return e;
}

} // namespace anisotropy
} // namespace fluidsurf
