// ClassRule.h - the last step of classification at one particle: its kClassLanes lanes of
// neighbour sums reduced in double, then the class rule (Classify.h). Plain C++ that nvcc also
// compiles for the device (like field/FieldMath.h), so the CPU and CUDA classes cannot drift apart;
// any change to the rounding here changes the band's topology.
#pragma once

#include "util/HostDevice.h"

#include <math.h>
#include <stdint.h>

namespace fluidsurf {
namespace classify {

enum ParticleClass : uint8_t { Interior = 0, Surface = 1, Splash = 2, Isolated = 3 };

/// The float lanes a particle's neighbour sums run on, on the CPU and the device alike:
/// candidate k (in the neighbourhood's order) adds to lane k % kClassLanes. Eight: one AVX
/// register (two SSE ones where the CPU has no AVX2, with the same sums).
constexpr int kClassLanes = 8;

struct ClassRule
{
    double poly6 = 0, gradientScale = 0; ///< see KernelConstants
    int splashNeighbours = 3, surfaceNeighbours = 25;
    double colorFieldThreshold = 0.9, colorGradientThreshold = 0.45;
};

struct ParticleSums
{
    uint32_t neighbours = 0; ///< other particles closer than h
    float colorField = 0;    ///< cf_i
    float gradient = 0;      ///< |grad cf_i| * h
    uint8_t cls = Interior;
};

/// The class rule at one particle, from its lane sums added up in double (count, V t^3 and
/// V t^2 d per axis, each the sum of its kClassLanes lanes in lane order, from +0).
FLUIDSURF_HD inline ParticleSums classifyTotals(double cnt, double sum, const double (&g)[3],
                                                const ClassRule& rule)
{
    ParticleSums s;
    // |grad cf| * h: dimensionless, 0 inside, 0.62 on a flat lattice face.
    s.gradient = float(rule.gradientScale * sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]));
    s.neighbours = uint32_t(cnt) - 1; // self is at distance 0
    s.colorField = float(sum * rule.poly6);
    if (s.neighbours == 0)
        s.cls = Isolated;
    else if (int(s.neighbours) < rule.splashNeighbours)
        s.cls = Splash;
    else if (int(s.neighbours) < rule.surfaceNeighbours ||
             s.colorField < rule.colorFieldThreshold || s.gradient > rule.colorGradientThreshold)
        s.cls = Surface;
    return s;
}

/// From per-lane sums (count, V t^3, V t^2 d per axis; lane l = candidates k with
/// k % kClassLanes == l, self included) to the particle's sums and class. L: anything indexable
/// by 0 .. kClassLanes - 1. (The CPU's AVX2 path adds the lanes up in registers, in the same
/// order: classify/Classify.cc.)
template <typename L>
FLUIDSURF_HD inline ParticleSums classifyLanes(const L& count, const L& cf, const L& gx,
                                               const L& gy, const L& gz, const ClassRule& rule)
{
    double cnt = 0, sum = 0, g[3] = {0, 0, 0};
    for (int l = 0; l < kClassLanes; ++l)
        cnt += count[l], sum += cf[l], g[0] += gx[l], g[1] += gy[l], g[2] += gz[l];
    return classifyTotals(cnt, sum, g, rule);
}

} // namespace classify
} // namespace fluidsurf
