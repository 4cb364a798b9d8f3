// Lanes.h - a few floats (or doubles) processed as one value, through the GCC/Clang vector
// extensions: explicit SIMD on any x86-64 (SSE2 baseline) without intrinsics. The hot loops of
// classify and field accumulate per lane and add the lanes in a fixed order at the end, so results
// do not depend on how work is split between threads.
#pragma once

#include <cstring>

namespace fluidsurf {
namespace util {

constexpr int kLanes = 4; // one SSE register: the field kernel's 14 accumulators fit in 16
typedef float Lanes __attribute__((vector_size(kLanes * sizeof(float))));

inline Lanes loadLanes(const float* p)
{
    Lanes v;
    std::memcpy(&v, p, sizeof(v));
    return v;
}

/// Twice as many: one AVX register. Only for code compiled for AVX2 (a target attribute, chosen
/// at run time): without AVX the compiler splits each operation in two.
constexpr int kWideLanes = 8;
typedef float WideLanes __attribute__((vector_size(kWideLanes * sizeof(float))));

/// Doubles the same way (decimation's quadrics): two in an SSE register, four in an AVX one
/// (for code compiled for AVX2 alone, as above).
typedef double Doubles __attribute__((vector_size(2 * sizeof(double))));
typedef double WideDoubles __attribute__((vector_size(4 * sizeof(double))));

/// Doubles a register for code that picks its width at run time: 4 (WideDoubles) where the CPU
/// has AVX2, else 2 (Doubles).
inline int doubleRegisterLanes()
{
    static const bool wide = __builtin_cpu_supports("avx2");
    return wide ? 4 : 2;
}

} // namespace util
} // namespace fluidsurf
