// BruteForce.h - an independent reference for the field tests: phi straight from the DESIGN.md
// formulas, in double precision, over every particle, with the Jacobian built term by term and
// its symmetric part's eigenvalues found by cyclic Jacobi rotations (not the closed form the
// library uses). Slow on purpose; no library code beyond ParticleSet.
#pragma once

#include <fluidsurf/ParticleSet.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <numeric>
#include <vector>

namespace fluidsurf {
namespace test {

struct ReferenceParams
{
    double radius, influence, smoothing, tLow = 0.4, tHigh = 3.5, background;
    bool ssp07 = true;
};

/// Largest eigenvalue of a symmetric 3x3 matrix by Jacobi rotations.
inline double jacobiLargestEigenvalue(std::array<std::array<double, 3>, 3> a)
{
    for (int sweep = 0; sweep < 50; ++sweep) {
        const double off = a[0][1] * a[0][1] + a[0][2] * a[0][2] + a[1][2] * a[1][2];
        if (off < 1e-30) break;
        for (int p = 0; p < 2; ++p)
            for (int q = p + 1; q < 3; ++q) {
                if (std::abs(a[p][q]) < 1e-300) continue;
                const double theta = (a[q][q] - a[p][p]) / (2 * a[p][q]);
                const double t =
                    (theta >= 0 ? 1 : -1) / (std::abs(theta) + std::sqrt(theta * theta + 1));
                const double c = 1 / std::sqrt(t * t + 1), s = t * c;
                for (int k = 0; k < 3; ++k) { // A <- A G
                    const double akp = a[k][p], akq = a[k][q];
                    a[k][p] = c * akp - s * akq;
                    a[k][q] = s * akp + c * akq;
                }
                for (int k = 0; k < 3; ++k) { // A <- G^T A
                    const double apk = a[p][k], aqk = a[q][k];
                    a[p][k] = c * apk - s * aqk;
                    a[q][k] = s * apk + c * aqk;
                }
            }
    }
    return std::max({a[0][0], a[1][1], a[2][2]});
}

/// phi at x over the given particles (radii: per particle, or empty for uniform).
inline double referencePhi(const std::vector<std::array<double, 3>>& pts,
                           const std::vector<double>& radii, const std::array<double, 3>& x,
                           const ReferenceParams& p)
{
    const double R = p.influence;
    double W = 0, xs[3] = {0, 0, 0}, rs = 0;
    std::vector<size_t> near;
    for (size_t j = 0; j < pts.size(); ++j) {
        double d2 = 0;
        for (int a = 0; a < 3; ++a)
            d2 += (x[a] - pts[j][a]) * (x[a] - pts[j][a]);
        const double s2 = d2 / (R * R);
        if (s2 >= 1) continue;
        const double w = std::pow(1 - s2, 3);
        W += w;
        for (int a = 0; a < 3; ++a)
            xs[a] += w * pts[j][a];
        rs += w * (radii.empty() ? p.radius : radii[j]);
        near.push_back(j);
    }
    if (W == 0) return p.background;
    double xbar[3];
    for (int a = 0; a < 3; ++a)
        xbar[a] = xs[a] / W;
    const double rbar = rs / W;
    double f = 1;
    if (p.ssp07) {
        std::array<std::array<double, 3>, 3> J{};
        for (size_t j : near) {
            double d2 = 0;
            for (int a = 0; a < 3; ++a)
                d2 += (x[a] - pts[j][a]) * (x[a] - pts[j][a]);
            const double s2 = d2 / (R * R);
            double grad[3];
            for (int b = 0; b < 3; ++b)
                grad[b] = -6 * (1 - s2) * (1 - s2) * (x[b] - pts[j][b]) / (R * R);
            for (int a = 0; a < 3; ++a)
                for (int b = 0; b < 3; ++b)
                    J[a][b] += (pts[j][a] - xbar[a]) * grad[b] / W;
        }
        std::array<std::array<double, 3>, 3> S{};
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                S[a][b] = 0.5 * (J[a][b] + J[b][a]);
        const double ev = jacobiLargestEigenvalue(S);
        if (ev >= p.tLow) {
            double g = (p.tHigh - ev) / (p.tHigh - p.tLow);
            g = std::min(1.0, std::max(0.0, g));
            f = g * g * g - 3 * g * g + 3 * g;
        }
    }
    double dist = 0;
    for (int a = 0; a < 3; ++a)
        dist += (x[a] - xbar[a]) * (x[a] - xbar[a]);
    const double phi = std::sqrt(dist) - rbar * f;
    return std::min(p.background, std::max(-p.background, phi));
}

/// Neighbour counts within h (strictly closer), by a sweep over x-sorted particles.
inline std::vector<int> referenceNeighbourCounts(const std::vector<std::array<double, 3>>& pts,
                                                 double h)
{
    std::vector<size_t> order(pts.size());
    std::iota(order.begin(), order.end(), 0);
    std::sort(order.begin(), order.end(),
              [&](size_t a, size_t b) { return pts[a][0] < pts[b][0]; });
    std::vector<int> count(pts.size(), 0);
    for (size_t i = 0; i < order.size(); ++i)
        for (size_t k = i + 1; k < order.size() && pts[order[k]][0] - pts[order[i]][0] < h; ++k) {
            const auto &a = pts[order[i]], &b = pts[order[k]];
            const double d2 = (a[0] - b[0]) * (a[0] - b[0]) + (a[1] - b[1]) * (a[1] - b[1]) +
                              (a[2] - b[2]) * (a[2] - b[2]);
            if (d2 < h * h) ++count[order[i]], ++count[order[k]];
        }
    return count;
}

} // namespace test
} // namespace fluidsurf
