// IncidenceTest.cc - util::buildIncidence against the table one thread makes by walking the items
// in order (each key's items appended as met): the same offsets and lists, item by item, for
// items whose keys are spread at random or come in runs (as a mesh's corners do), with a key
// named twice by one item, keys no item names, no items, and 1 to 8 threads (so 1 to 8 runs of
// items: the table must not depend on them).
#include "util/Incidence.h"

#include <gtest/gtest.h>

#include <tbb/task_arena.h>

#include <array>
#include <cstdint>
#include <random>
#include <vector>

using fluidsurf::util::buildIncidence;

namespace {

using Keys = std::vector<std::array<uint32_t, 3>>;

/// The reference: each key's items in item order, by appending.
void reference(const Keys& items, uint32_t keys, std::vector<uint32_t>& start,
               std::vector<uint32_t>& list)
{
    std::vector<std::vector<uint32_t>> of(keys);
    for (size_t i = 0; i < items.size(); ++i)
        for (uint32_t k : items[i])
            of[k].push_back(uint32_t(i));
    start.assign(1, 0);
    list.clear();
    for (const auto& l : of) {
        list.insert(list.end(), l.begin(), l.end());
        start.push_back(uint32_t(list.size()));
    }
}

} // namespace

TEST(Incidence, SameTableAsOneThreadWalkingTheItems)
{
    std::mt19937 rng(11);
    for (const size_t n : {size_t(0), size_t(1), size_t(5), size_t(1000), size_t(200000)}) {
        for (int kind = 0; kind < 3; ++kind) {
            const uint32_t keys = uint32_t(n / 2 + 3);
            Keys items(n);
            for (size_t i = 0; i < n; ++i)
                for (int c = 0; c < 3; ++c) {
                    if (kind == 0) // anywhere
                        items[i][c] = uint32_t(rng() % keys);
                    else if (kind == 1) // in runs, as a mesh's triangles name their corners
                        items[i][c] = uint32_t(std::min<size_t>(keys - 1, i / 2 + rng() % 8));
                    else // a key named twice by one item now and then
                        items[i][c] =
                            c == 2 && rng() % 4 == 0 ? items[i][0] : uint32_t(rng() % keys);
                }
            std::vector<uint32_t> wantStart, wantList;
            reference(items, keys, wantStart, wantList);
            for (const int threads : {1, 2, 3, 8}) {
                std::vector<uint32_t> start, list;
                tbb::task_arena(threads).execute([&] {
                    buildIncidence(
                        n, keys,
                        [&](size_t i, auto&& emit) {
                            for (uint32_t k : items[i])
                                emit(k);
                        },
                        start, list);
                });
                EXPECT_EQ(start, wantStart) << n << " items, kind " << kind << ", " << threads;
                EXPECT_EQ(list, wantList) << n << " items, kind " << kind << ", " << threads;
            }
        }
    }
}
