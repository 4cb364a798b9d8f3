// Points4.h - four consecutive points' coordinates split by axis into SSE registers: the load
// that the vectorised loops over particles (the cell index's keys, the field's gather) start
// from. Three 4-float loads and six shuffles; lane l holds point l.
#pragma once

#include <fluidsurf/Vec3.h>

#include <immintrin.h>

namespace fluidsurf {
namespace util {

/// p[0, 4)'s x, y and z (p[0] .. p[3] must be readable).
inline void splitPoints4(const Vec3f* p, __m128& xs, __m128& ys, __m128& zs)
{
    static_assert(sizeof(Vec3f) == 3 * sizeof(float));
    // x0 y0 z0 x1 | y1 z1 x2 y2 | z2 x3 y3 z3: each axis' first two from a and b, its last two
    // from b and c, then the four put together
    const float* f = reinterpret_cast<const float*>(p);
    const __m128 a = _mm_loadu_ps(f), b = _mm_loadu_ps(f + 4), c = _mm_loadu_ps(f + 8);
    xs = _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(2, 2, 3, 0)),
                        _mm_shuffle_ps(b, c, _MM_SHUFFLE(1, 1, 2, 2)), _MM_SHUFFLE(2, 0, 1, 0));
    ys = _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(3, 0, 0, 1)),
                        _mm_shuffle_ps(b, c, _MM_SHUFFLE(2, 2, 3, 3)), _MM_SHUFFLE(2, 0, 2, 0));
    zs = _mm_shuffle_ps(_mm_shuffle_ps(a, b, _MM_SHUFFLE(1, 1, 2, 2)),
                        _mm_shuffle_ps(c, c, _MM_SHUFFLE(3, 3, 0, 0)), _MM_SHUFFLE(2, 0, 2, 0));
}

} // namespace util
} // namespace fluidsurf
