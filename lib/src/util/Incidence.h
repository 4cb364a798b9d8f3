// Incidence.h - "which items touch each key", as offsets and one list (compressed rows), made
// on all threads: the vertex -> triangle table of post-processing, the point -> edge lists of
// Loop subdivision. Serial, these counting sorts were most of what did not scale there.
#pragma once

#include "util/Memory.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include <algorithm>
#include <cstdint>
#include <utility>
#include <vector>

namespace fluidsurf {
namespace util {

/// For items 0 .. items - 1, each naming some keys below `keys` (keysOf(item, emit) calls
/// emit(key) for each, a key named twice counted twice): start (keys + 1 offsets) and list,
/// where key k's items are list[start[k], start[k + 1]) in ascending order, the table one
/// thread would make by walking the items in order.
///
/// The items are cut into a few runs, each counted and then written by one task into its own
/// row of counts, so neither pass needs an atomic, and each key's list comes out in item order
/// (run by run) without a sort. The atomic counts and slots of the lists' first form, and the
/// sort of each list after, were most of the table's time (on 2 cores, 0.042 s of 0.047 s for
/// the 13.1M drop's processed mesh): an atomic add costs some twenty plain ones here. The runs
/// are as many as the threads (at most kMaxRuns), and fewer where their rows would hold more
/// than kRowsPerItem counts an item; the table is the same for any number of them. (At most 8,
/// the four tables of decimation's set-up took 36-44 ms of the 13.1M drop on 16 threads; with
/// up to 16, 24-33 ms. A table of all the vertices stays at 8 by the rows' rule.)
/// Vector: a vector of uint32_t (util::NoInitVector: not zeroed by one thread before the
/// threads fill it).
template <typename KeysOf, typename Vector>
void buildIncidence(size_t items, uint32_t keys, KeysOf keysOf, Vector& start, Vector& list)
{
    constexpr size_t kMaxRuns = 16, kRowsPerItem = 4, kKeyBlock = size_t(1) << 14;
    size_t runs = std::clamp<size_t>(size_t(tbb::this_task_arena::max_concurrency()), 1, kMaxRuns);
    while (runs > 1 && runs * size_t(keys) > kRowsPerItem * items)
        --runs;
    const size_t per = (items + runs - 1) / runs;
    // at[r * keys + k]: run r's count of key k, then where its next item of key k goes in list
    NoInitVector<uint32_t> at(runs * size_t(keys));
    auto forRun = [&](size_t r, auto&& f) {
        for (size_t i = r * per; i < std::min(items, (r + 1) * per); ++i)
            keysOf(i, [&](uint32_t key) { f(key, uint32_t(i)); });
    };
    tbb::parallel_for(size_t(0), runs, [&](size_t r) {
        uint32_t* const row = &at[r * size_t(keys)];
        std::fill(row, row + keys, 0u);
        forRun(r, [&](uint32_t k, uint32_t) { ++row[k]; });
    });
    // each key's start and each run's first slot for it: blocks of keys summed on all threads,
    // the blocks' sums added up in order, then each block's offsets from its sum
    const size_t blocks = (size_t(keys) + kKeyBlock - 1) / kKeyBlock;
    std::vector<size_t> before(blocks + 1, 0);
    tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
        size_t sum = 0;
        for (size_t k = b * kKeyBlock; k < std::min(size_t(keys), (b + 1) * kKeyBlock); ++k)
            for (size_t r = 0; r < runs; ++r)
                sum += at[r * keys + k];
        before[b + 1] = sum;
    });
    for (size_t b = 0; b < blocks; ++b)
        before[b + 1] += before[b];
    start.resize(size_t(keys) + 1);
    tbb::parallel_for(size_t(0), blocks, [&](size_t b) {
        size_t next = before[b];
        for (size_t k = b * kKeyBlock; k < std::min(size_t(keys), (b + 1) * kKeyBlock); ++k) {
            start[k] = uint32_t(next);
            for (size_t r = 0; r < runs; ++r)
                next += std::exchange(at[r * keys + k], uint32_t(next));
        }
    });
    start[keys] = uint32_t(before[blocks]);
    list.resize(before[blocks]);
    tbb::parallel_for(size_t(0), runs, [&](size_t r) {
        uint32_t* const row = &at[r * size_t(keys)];
        forRun(r, [&](uint32_t k, uint32_t i) { list[row[k]++] = i; });
    });
}

} // namespace util
} // namespace fluidsurf
