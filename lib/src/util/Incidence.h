// Incidence.h - "which items touch each key", as offsets and one list (compressed rows), made
// on all threads: the vertex -> triangle table of post-processing, the point -> edge lists of
// Loop subdivision. Serial, these counting sorts were most of what did not scale there.
#pragma once

#include "util/Memory.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace fluidsurf {
namespace util {

/// For items 0 .. items - 1, each naming some keys below `keys` (keysOf(item, emit) calls
/// emit(key) for each, a key named twice counted twice): start (keys + 1 offsets) and list,
/// where key k's items are list[start[k], start[k + 1]) in ascending order, the table one
/// thread would make by walking the items in order. The counts and the slots taken are atomic,
/// so the lists fill in any order; each is sorted after (few items a key: insertion sort).
/// Vector: a vector of uint32_t (util::NoInitVector: the list is not zeroed by one thread
/// before the threads fill it; the counts are zeroed on all threads).
template <typename KeysOf, typename Vector>
void buildIncidence(size_t items, uint32_t keys, KeysOf keysOf, Vector& start, Vector& list)
{
    const auto overItems = [&](auto&& f) {
        tbb::parallel_for(tbb::blocked_range<size_t>(0, items),
                          [&](const tbb::blocked_range<size_t>& r) {
                              for (size_t i = r.begin(); i != r.end(); ++i)
                                  keysOf(i, [&](uint32_t key) { f(key, uint32_t(i)); });
                          });
    };
    start.resize(size_t(keys) + 1);
    fillInParallel(start, 0u);
    overItems(
        [&](uint32_t k, uint32_t) { __atomic_fetch_add(&start[k + 1], 1u, __ATOMIC_RELAXED); });
    for (size_t k = 0; k < keys; ++k)
        start[k + 1] += start[k];
    list.resize(start.back());
    // each key's slots taken from its start, which so moves to the next key's; shifted back after
    overItems([&](uint32_t k, uint32_t i) {
        list[__atomic_fetch_add(&start[k], 1u, __ATOMIC_RELAXED)] = i;
    });
    for (size_t k = keys; k > 0; --k)
        start[k] = start[k - 1];
    start[0] = 0;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, keys),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t k = r.begin(); k != r.end(); ++k)
                              for (uint32_t i = start[k] + 1; i < start[k + 1]; ++i)
                                  for (uint32_t j = i; j > start[k] && list[j - 1] > list[j]; --j)
                                      std::swap(list[j - 1], list[j]);
                      });
}

} // namespace util
} // namespace fluidsurf
