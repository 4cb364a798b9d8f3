// NthSmallest.h - the k-th smallest of the values a predicate accepts, on all threads: what
// std::nth_element finds, without one thread first copying the accepted values out and then
// partitioning them (the decimation's pass threshold, from a million sampled errors: the
// serial part of that step, a third of a pass' set-up on 16 cores).
//
// Non-negative floats order like their bits, so a histogram of the top 16 bits, counted per
// thread, finds the bucket that holds the k-th; only that bucket's values are then gathered and
// partitioned. The k-th smallest is one value whatever finds it, so the answer is the same bits
// as std::nth_element's, for any thread count.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <cstring>
#include <vector>

namespace fluidsurf {
namespace util {

/// Into `out`, the k-th smallest (from 0) of the v[i], i < n, that accept(v[i]) takes, which
/// must all be non-negative and not NaN (+0 and -0 are not told apart: take -0 out); false,
/// out untouched, when it takes k or fewer.
template <typename Accept>
bool nthSmallest(const float* v, size_t n, Accept accept, size_t k, float& out)
{
    constexpr int kShift = 16;
    constexpr size_t kBuckets = size_t(1) << (32 - kShift);
    auto bitsOf = [](float x) {
        uint32_t b;
        std::memcpy(&b, &x, sizeof b);
        return b;
    };
    tbb::enumerable_thread_specific<std::vector<uint32_t>> counts(
        [] { return std::vector<uint32_t>(kBuckets, 0); });
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 14),
                      [&](const tbb::blocked_range<size_t>& r) {
                          std::vector<uint32_t>& c = counts.local();
                          for (size_t i = r.begin(); i != r.end(); ++i)
                              if (accept(v[i])) ++c[bitsOf(v[i]) >> kShift];
                      });
    std::vector<size_t> total(kBuckets, 0);
    for (const std::vector<uint32_t>& c : counts)
        for (size_t b = 0; b < kBuckets; ++b)
            total[b] += c[b];
    size_t below = 0, bucket = 0;
    while (bucket < kBuckets && below + total[bucket] <= k)
        below += total[bucket++];
    if (bucket == kBuckets) return false; // k or fewer accepted
    tbb::enumerable_thread_specific<std::vector<float>> found;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 14),
                      [&](const tbb::blocked_range<size_t>& r) {
                          std::vector<float>& f = found.local();
                          for (size_t i = r.begin(); i != r.end(); ++i)
                              if (bitsOf(v[i]) >> kShift == bucket && accept(v[i]))
                                  f.push_back(v[i]);
                      });
    std::vector<float> inBucket;
    for (const std::vector<float>& f : found)
        inBucket.insert(inBucket.end(), f.begin(), f.end());
    std::nth_element(inBucket.begin(), inBucket.begin() + (k - below), inBucket.end());
    out = inBucket[k - below];
    return true;
}

} // namespace util
} // namespace fluidsurf
