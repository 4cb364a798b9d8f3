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

/// Lanes [first, first + the lanes of V) of the batch.
template <typename V>
FLUIDSURF_QUADRIC_INLINE void errorsOf(const CollapseBatch& b, int first, double* out)
{
    constexpr int kFields = CollapseBatch::kFields;
    const CollapseBatch::Lanes& in = b.lanes();
    V qa[kFields], qb[kFields], pa[3], pb[3];
    for (int k = 0; k < kFields; ++k) {
        std::memcpy(&qa[k], &in.qa[k][first], sizeof(V));
        std::memcpy(&qb[k], &in.qb[k][first], sizeof(V));
    }
    for (int k = 0; k < 3; ++k) {
        std::memcpy(&pa[k], &in.pa[k][first], sizeof(V));
        std::memcpy(&pb[k], &in.pb[k][first], sizeof(V));
    }
    const BasicQuadric<V> a{qa[0], qa[1], qa[2], qa[3], qa[4], qa[5],
                            qa[6], qa[7], qa[8], qa[9], qa[10]};
    const BasicQuadric<V> c{qb[0], qb[1], qb[2], qb[3], qb[4], qb[5],
                            qb[6], qb[7], qb[8], qb[9], qb[10]};
    V point[3], error;
    bestCollapse(a, pa, c, pb, point, error);
    std::memcpy(out + first, &error, sizeof error);
}

__attribute__((target("avx2"))) void wideErrors(const CollapseBatch& b, double* out)
{
    errorsOf<util::WideDoubles>(b, 0, out);
}

void narrowErrors(const CollapseBatch& b, int n, double* out)
{
    errorsOf<util::Doubles>(b, 0, out);
    if (n > 2) errorsOf<util::Doubles>(b, 2, out);
}

} // namespace

int CollapseBatch::registerLanes()
{
    static const bool wide = __builtin_cpu_supports("avx2");
    return wide ? 4 : 2;
}

void CollapseBatch::errors(int n, double* out, int lanes) const
{
    if (lanes != 2 && lanes != 4) throw ValueError("CollapseBatch: 2 or 4 doubles a register");
    if (lanes > registerLanes())
        throw ValueError("CollapseBatch: 4 doubles a register need a CPU with AVX2");
    double all[kSize];
    if (lanes == 4)
        wideErrors(*this, all);
    else
        narrowErrors(*this, n, all);
    std::memcpy(out, all, size_t(n) * sizeof(double));
}

} // namespace detail
} // namespace post
} // namespace fluidsurf
