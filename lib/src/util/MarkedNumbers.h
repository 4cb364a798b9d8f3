// MarkedNumbers.h - numbering the marked positions of a range in order, on all threads (the
// particle index's occupied cells and kept particles, the band's seeds, Loop's edges, the
// components' roots, decimation's kept points): each fixed chunk
// counts its marks, then walks again from where the earlier chunks' end. The same numbers as
// one thread counting from the start, for any thread count.
#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <vector>

namespace fluidsurf {
namespace util {

/// marked(i) for i in [0, n): asked twice a position, so it must give the same answer twice.
template <typename Marked> class MarkedNumbers
{
public:
    MarkedNumbers(size_t n, Marked marked)
        : mN(n), mMarked(std::move(marked)), mBefore((n + kChunk - 1) / kChunk + 1, 0)
    {
        const size_t chunks = mBefore.size() - 1;
        tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
            for (size_t i = c * kChunk; i < std::min(mN, (c + 1) * kChunk); ++i)
                mBefore[c + 1] += mMarked(i) ? 1 : 0;
        });
        for (size_t c = 0; c < chunks; ++c)
            mBefore[c + 1] += mBefore[c];
    }

    /// How many positions are marked.
    size_t count() const { return mBefore.back(); }

    /// f(i, marked, k) for every position, in parallel: k the number of marked positions up to
    /// and including i (so a marked i is number k - 1).
    template <typename F> void forEach(F&& f) const
    {
        tbb::parallel_for(size_t(0), mBefore.size() - 1, [&](size_t c) {
            size_t k = mBefore[c];
            for (size_t i = c * kChunk; i < std::min(mN, (c + 1) * kChunk); ++i) {
                const bool m = mMarked(i);
                k += m ? 1 : 0;
                f(i, m, k);
            }
        });
    }

    /// f(chunk, begin, end, before) for every chunk [begin, end) of the positions, in
    /// parallel: `before` marked positions come before it (its first marked one is number
    /// `before`).
    template <typename F> void forEachChunk(F&& f) const
    {
        tbb::parallel_for(size_t(0), mBefore.size() - 1, [&](size_t c) {
            f(c, c * kChunk, std::min(mN, (c + 1) * kChunk), mBefore[c]);
        });
    }
    size_t chunks() const { return mBefore.size() - 1; }

private:
    static constexpr size_t kChunk = size_t(1) << 16;
    size_t mN;
    Marked mMarked;
    std::vector<size_t> mBefore; ///< marked positions before each chunk
};

} // namespace util
} // namespace fluidsurf
