// Angle.h - the angles atan2(y, x) with y > 0, many at once: a triangle's angle at a corner
// from its sides' cross and dot products, for angle-weighted normals (post/Normals).
//
// Why not std::atan2: on the 13.1M-particle drop the final normals call it 9.4 million times,
// 22 ns each here, two thirds of that step. These run two or four to a register, about 5 ns
// each, within 2 ulp of glibc's (four in five the same double; see AngleTest).
#pragma once

#include <cstddef>

namespace fluidsurf {
namespace util {

/// angle[i] = atan2(y[i], x[i]) in [0, pi] for y[i] > 0 and any finite x[i] (where y[i] <= 0,
/// something the caller must not use). `lanes`: doubles a register, 2 or 4 (4 needs AVX2;
/// doubleRegisterLanes()); the same bits either way.
void angles(const double* y, const double* x, double* angle, size_t n, int lanes);
/// The same at the CPU's widest register.
void angles(const double* y, const double* x, double* angle, size_t n);

} // namespace util
} // namespace fluidsurf
