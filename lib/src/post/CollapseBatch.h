// CollapseBatch.h - the best collapse (post/Quadric.h, bestCollapse) of several edges at once,
// one a SIMD lane: the decimation finds the error of every edge it puts in a heap, a third of a
// collapse's work and most of a block's set-up (four lanes where the CPU has AVX2, else two
// registers of two).
#pragma once

#include "post/Quadric.h"

#include <cstdint>
#include <cstring>

namespace fluidsurf {
namespace post {
namespace detail {

struct Collapse
{
    Vec3d point;
    double error; ///< area-weighted mean squared distance to the planes
};

/// The collapse of an edge whose ends have the planes qa and qb (each about its own point, pa
/// and pb) to the point of least error, found from the edge's middle. Inlined for each T
/// (BasicQuadric), so that a lane of a vector gives a double's bits.
template <typename T>
FLUIDSURF_QUADRIC_INLINE void bestCollapse(const BasicQuadric<T>& qa, const T (&pa)[3],
                                           const BasicQuadric<T>& qb, const T (&pb)[3],
                                           T (&point)[3], T& error)
{
    const T middle[3] = {(pa[0] + pb[0]) * 0.5, (pa[1] + pb[1]) * 0.5, (pa[2] + pb[2]) * 0.5};
    const BasicQuadric<T> q = qa.movedTo(middle[0] - pa[0], middle[1] - pa[1], middle[2] - pa[2]) +
                              qb.movedTo(middle[0] - pb[0], middle[1] - pb[1], middle[2] - pb[2]);
    const T zero[3] = {T{}, T{}, T{}};
    T x[3]; // from the middle
    q.minimizer(zero, x);
    for (int k = 0; k < 3; ++k)
        point[k] = middle[k] + x[k];
    error = q.w > 0 ? q.error(x[0], x[1], x[2]) / q.w : T{};
}

inline Collapse bestCollapse(const Quadric& qa, const Vec3d& pa, const Quadric& qb, const Vec3d& pb)
{
    const double a[3] = {pa[0], pa[1], pa[2]}, b[3] = {pb[0], pb[1], pb[2]};
    double point[3], error;
    bestCollapse(qa, a, qb, b, point, error);
    return {Vec3d(point[0], point[1], point[2]), error};
}

/// Up to kSize edges: set() each, then errors() (or collapses(), with the points) gives what
/// bestCollapse would, bit for bit.
class CollapseBatch
{
public:
    static constexpr int kSize = 4;

    /// Lane i: the edge (qa at pa, qb at pb), as bestCollapse takes it.
    void set(int i, const Quadric& qa, const Vec3d& pa, const Quadric& qb, const Vec3d& pb)
    {
        static_assert(sizeof(Quadric) == kFields * sizeof(double), "a quadric: 11 doubles");
        static_assert(sizeof(Vec3d) == 3 * sizeof(double), "a point: 3 doubles");
        storePairs(mLanes.qa[i], &qa, kFields);
        storePairs(mLanes.qb[i], &qb, kFields);
        storePairs(mLanes.pa[i], &pa, 3);
        storePairs(mLanes.pb[i], &pb, 3);
    }
    /// The doubles a register holds where the CPU has AVX2 (4), else 2 (SSE).
    static int registerLanes();
    /// The errors of lanes [0, n), n <= kSize, with `lanes` doubles a register: 2, or 4 where
    /// registerLanes() is 4 (tests run both); ValueError otherwise.
    void errors(int n, double* out, int lanes = registerLanes()) const;
    /// The collapses of lanes [0, n), points and errors, as errors() finds them.
    void collapses(int n, Collapse* out, int lanes = registerLanes()) const;

    static constexpr int kFields = 11; ///< a quadric's doubles
    /// The lanes as set, a row each: a quadric's fields in order (a00 ... w), a point's x, y,
    /// z, each padded with zeros to whole pairs. Written a pair at a time (16-byte stores) and
    /// read so (errors() interleaves two lanes' pairs into one register a field): written field
    /// by field into each field's row of lanes, as before, each register's load met four 8-byte
    /// stores that could not be forwarded to it, and waited for them (the batch's copies were
    /// 7% of a decimation's samples).
    struct Lanes
    {
        double qa[kSize][kFields + 1], qb[kSize][kFields + 1], pa[kSize][4], pb[kSize][4];
    };
    const Lanes& lanes() const { return mLanes; }

private:
    /// The n doubles at `from` into `row`, a pair at a time, the last pair padded with +0.
    static void storePairs(double* row, const void* from, int n)
    {
        typedef double Pair __attribute__((vector_size(16)));
        const auto* d = static_cast<const char*>(from);
        for (int k = 0; k + 1 < n; k += 2) {
            Pair p;
            std::memcpy(&p, d + k * sizeof(double), sizeof p);
            std::memcpy(row + k, &p, sizeof p);
        }
        if (n % 2) {
            Pair p{0.0, 0.0};
            std::memcpy(&p, d + (n - 1) * sizeof(double), sizeof(double));
            std::memcpy(row + n - 1, &p, sizeof p);
        }
    }

    // (zeroed once: lanes past n compute on whatever an earlier batch left, never undefined)
    alignas(32) Lanes mLanes{};
};

} // namespace detail
} // namespace post
} // namespace fluidsurf
