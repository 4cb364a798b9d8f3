// RadixSort.h - a stable, parallel LSD radix sort on an unsigned key of known width: items with
// equal keys keep their order, so items already in index order come out sorted by (key, index),
// the order a comparison sort on both gives, at a third of its time or less. Parallel over fixed
// chunks of items: each chunk counts its digits, then writes its items, in order, from where
// the same digit's earlier chunks end; the result is the same for any thread count.
#pragma once

#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace fluidsurf {
namespace util {

/// Sorts items by key(item) (an unsigned integer below 2^keyBits), stably. Rounds of at most 11
/// bits; a round where every item has the same digit is skipped.
/// The scratch array has items' allocator (util::NoInitAllocator: not zeroed first).
template <typename T, typename Alloc, typename KeyOf>
void radixSortStable(std::vector<T, Alloc>& items, int keyBits, KeyOf key)
{
    const size_t n = items.size();
    if (n < 2 || keyBits <= 0) return;
    constexpr size_t kChunk = size_t(1) << 16;
    const int rounds = (keyBits + 10) / 11, digitBits = (keyBits + rounds - 1) / rounds;
    const size_t digits = size_t(1) << digitBits, chunks = (n + kChunk - 1) / kChunk;
    const uint64_t mask = digits - 1;
    std::vector<T, Alloc> other(n);
    std::vector<size_t> at(chunks * digits);
    for (int round = 0; round < rounds; ++round) {
        const int shift = digitBits * round;
        std::fill(at.begin(), at.end(), size_t(0));
        tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
            size_t* count = &at[c * digits];
            for (size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i)
                ++count[uint64_t(key(items[i])) >> shift & mask];
        });
        const uint64_t first = uint64_t(key(items[0])) >> shift & mask;
        size_t sum = 0;
        for (size_t c = 0; c < chunks; ++c)
            sum += at[c * digits + first];
        if (sum == n) continue; // one digit for all
        sum = 0;
        for (size_t d = 0; d < digits; ++d)
            for (size_t c = 0; c < chunks; ++c)
                sum += std::exchange(at[c * digits + d], sum);
        tbb::parallel_for(size_t(0), chunks, [&](size_t c) {
            size_t* to = &at[c * digits];
            for (size_t i = c * kChunk; i < std::min(n, (c + 1) * kChunk); ++i)
                other[to[uint64_t(key(items[i])) >> shift & mask]++] = items[i];
        });
        items.swap(other);
    }
}

} // namespace util
} // namespace fluidsurf
