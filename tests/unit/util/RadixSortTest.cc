// util::radixSortStable against std::stable_sort: random keys of several widths (one round, a
// ragged last round, 63 bits), few distinct keys (long runs of equal keys keep their order), a
// digit shared by every item (its round skipped), and more items than one chunk.
#include "util/RadixSort.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <random>

namespace {

struct Item
{
    uint64_t key;
    uint32_t index;
    bool operator==(const Item& o) const { return key == o.key && index == o.index; }
};

void check(int keyBits, size_t n, uint64_t distinct, uint64_t sharedHighBits, uint32_t seed)
{
    std::mt19937_64 rng(seed);
    std::vector<Item> items(n);
    const uint64_t range = keyBits == 64 ? ~uint64_t(0) : (uint64_t(1) << keyBits) - 1;
    for (size_t i = 0; i < n; ++i) {
        uint64_t k = rng() & range;
        if (distinct) k = (rng() % distinct) * (range / distinct);
        items[i] = {(k & ~sharedHighBits) | sharedHighBits, uint32_t(i)};
    }
    std::vector<Item> expected = items;
    std::stable_sort(expected.begin(), expected.end(),
                     [](const Item& a, const Item& b) { return a.key < b.key; });
    fluidsurf::util::radixSortStable(items, keyBits, [](const Item& it) { return it.key; });
    ASSERT_EQ(items.size(), expected.size());
    for (size_t i = 0; i < n; ++i)
        ASSERT_EQ(items[i], expected[i]) << "item " << i << ", " << keyBits << " bits";
}

} // namespace

TEST(RadixSort, StableSortByKeyOfAnyWidth)
{
    check(8, 1000, 0, 0, 1);                // one round
    check(30, 200000, 0, 0, 2);             // three rounds, several chunks
    check(24, 150000, 7, 0, 3);             // seven keys: long runs of equal keys
    check(63, 70000, 0, 0, 4);              // six rounds
    check(33, 90000, 0, 0x1ffc00000ull, 5); // the top round's digit the same for all: skipped
    check(20, 1, 0, 0, 6);                  // one item
    std::vector<Item> none;
    fluidsurf::util::radixSortStable(none, 20, [](const Item& it) { return it.key; });
    EXPECT_TRUE(none.empty());
}
