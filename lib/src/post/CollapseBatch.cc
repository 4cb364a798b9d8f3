// CollapseBatch.cc - several edges' collapses at once (see CollapseBatch.h).
//
// The vector types here never cross a call (everything is inlined into the functions compiled
// for their target), so GCC's note that their ABI differs without AVX does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"

#include "post/CollapseBatch.h"

#include "util/Lanes.h"

#include <fluidsurf/Error.h>

#include <cstring>

namespace fluidsurf {
namespace post {
namespace detail {
namespace {

/// Fields [0, n) of lanes [first, first + the lanes of V) from their rows (CollapseBatch::Lanes),
/// field k of every lane into out[k]: each pair of a row is loaded as set() stored it, and two
/// lanes' pairs interleave into a pair of fields, (a0 a1), (b0 b1) -> (a0 b0), (a1 b1) (with four
/// lanes, lanes 2 and 3 in the upper halves).
template <typename V, size_t kRow>
FLUIDSURF_QUADRIC_INLINE void fieldsOf(const double (*rows)[kRow], int first, int n, V* out)
{
    typedef double Pair __attribute__((vector_size(16)));
    auto pair = [&](int lane, int k) {
        Pair p;
        std::memcpy(&p, &rows[first + lane][k], sizeof p);
        return p;
    };
    for (int k = 0; k < n; k += 2) {
        V a, b, lo, hi;
        if constexpr (sizeof(V) == sizeof(Pair)) {
            a = pair(0, k), b = pair(1, k);
            lo = __builtin_shufflevector(a, b, 0, 2), hi = __builtin_shufflevector(a, b, 1, 3);
        } else {
            a = __builtin_shufflevector(pair(0, k), pair(2, k), 0, 1, 2, 3);
            b = __builtin_shufflevector(pair(1, k), pair(3, k), 0, 1, 2, 3);
            lo = __builtin_shufflevector(a, b, 0, 4, 2, 6);
            hi = __builtin_shufflevector(a, b, 1, 5, 3, 7);
        }
        out[k] = lo;
        if (k + 1 < n) out[k + 1] = hi;
    }
}

/// Lanes [first, first + the lanes of V) of the batch: their errors into out, and their points
/// into points (points[k][lane], if given).
template <typename V>
FLUIDSURF_QUADRIC_INLINE void errorsOf(const CollapseBatch& b, int first, double* out,
                                       double (*points)[CollapseBatch::kSize])
{
    constexpr int kFields = CollapseBatch::kFields;
    const CollapseBatch::Lanes& in = b.lanes();
    V qa[kFields], qb[kFields], pa[3], pb[3];
    fieldsOf(in.qa, first, kFields, qa);
    fieldsOf(in.qb, first, kFields, qb);
    fieldsOf(in.pa, first, 3, pa);
    fieldsOf(in.pb, first, 3, pb);
    const BasicQuadric<V> a{qa[0], qa[1], qa[2], qa[3], qa[4], qa[5],
                            qa[6], qa[7], qa[8], qa[9], qa[10]};
    const BasicQuadric<V> c{qb[0], qb[1], qb[2], qb[3], qb[4], qb[5],
                            qb[6], qb[7], qb[8], qb[9], qb[10]};
    V point[3], error;
    bestCollapse(a, pa, c, pb, point, error);
    std::memcpy(out + first, &error, sizeof error);
    if (points)
        for (int k = 0; k < 3; ++k)
            std::memcpy(&points[k][first], &point[k], sizeof(V));
}

__attribute__((target("avx2"))) void wideErrors(const CollapseBatch& b, double* out,
                                                double (*points)[CollapseBatch::kSize])
{
    errorsOf<util::WideDoubles>(b, 0, out, points);
}

void narrowErrors(const CollapseBatch& b, int n, double* out,
                  double (*points)[CollapseBatch::kSize])
{
    errorsOf<util::Doubles>(b, 0, out, points);
    if (n > 2) errorsOf<util::Doubles>(b, 2, out, points);
}

/// lanes: 2, or 4 where the CPU has AVX2 (see CollapseBatch::errors).
void checkLanes(int lanes)
{
    if (lanes != 2 && lanes != 4) throw ValueError("CollapseBatch: 2 or 4 doubles a register");
    if (lanes > CollapseBatch::registerLanes())
        throw ValueError("CollapseBatch: 4 doubles a register need a CPU with AVX2");
}

} // namespace

int CollapseBatch::registerLanes()
{
    return util::doubleRegisterLanes();
}

void CollapseBatch::errors(int n, double* out, int lanes) const
{
    checkLanes(lanes);
    double all[kSize];
    if (lanes == 4)
        wideErrors(*this, all, nullptr);
    else
        narrowErrors(*this, n, all, nullptr);
    std::memcpy(out, all, size_t(n) * sizeof(double));
}

void CollapseBatch::collapses(int n, Collapse* out, int lanes) const
{
    checkLanes(lanes);
    double errors[kSize], points[3][kSize];
    if (lanes == 4)
        wideErrors(*this, errors, points);
    else
        narrowErrors(*this, n, errors, points);
    for (int l = 0; l < n; ++l)
        out[l] = {Vec3d(points[0][l], points[1][l], points[2][l]), errors[l]};
}

} // namespace detail
} // namespace post
} // namespace fluidsurf
