// RankHeapTest.cc - decimation's heap (post/DecimateBlock.h's RankHeap) against a sorted
// reference: built at once, then pushes and pops interleaved, it hands out the smallest rank
// every time, ties included.
#include "post/DecimateBlock.h"

#include <gtest/gtest.h>

#include <random>
#include <set>

using fluidsurf::post::detail::RankHeap;

namespace {

struct Item
{
    uint64_t key;
    uint32_t tag;
    unsigned __int128 rank() const { return (unsigned __int128)key << 64 | tag; }
};

} // namespace

TEST(RankHeap, PopsInRankOrderThroughPushesAndPops)
{
    std::mt19937_64 rng(3);
    for (const size_t start : {0, 1, 2, 5, 100, 4000}) {
        std::vector<Item> items;
        std::multiset<unsigned __int128> reference;
        for (size_t i = 0; i < start; ++i) {
            const Item it{rng() % 50, uint32_t(rng() % 3)}; // many equal ranks
            items.push_back(it);
            reference.insert(it.rank());
        }
        RankHeap<Item> heap;
        heap.assign(std::move(items));
        size_t popped = 0, wrong = 0;
        for (int step = 0; step < 20000; ++step) {
            if (rng() % 3 == 0 || heap.empty()) { // a push a third of the time
                const Item it{rng() % 50, uint32_t(rng() % 3)};
                heap.push(it);
                reference.insert(it.rank());
                continue;
            }
            ASSERT_FALSE(reference.empty());
            wrong += heap.top().rank() != *reference.begin();
            reference.erase(reference.begin());
            heap.pop();
            ++popped;
        }
        while (!heap.empty()) {
            wrong += heap.top().rank() != *reference.begin();
            reference.erase(reference.begin());
            heap.pop(), ++popped;
        }
        EXPECT_TRUE(reference.empty()) << start;
        EXPECT_EQ(wrong, 0u) << "of " << popped << " pops, starting from " << start;
    }
}

// Decimation rids its heap of stale entries now and then (Block::run): what is left must pop in
// rank order, the same order as had the removed entries stayed and been skipped.
TEST(RankHeap, RemoveIfKeepsTheRestInRankOrder)
{
    std::mt19937_64 rng(5);
    for (const size_t start : {0, 1, 7, 3000}) {
        std::vector<Item> items;
        std::multiset<unsigned __int128> reference;
        for (size_t i = 0; i < start; ++i) {
            const Item it{rng() % 500, uint32_t(rng() % 4)};
            items.push_back(it);
            reference.insert(it.rank());
        }
        RankHeap<Item> heap;
        heap.assign(std::move(items));
        size_t popped = 0, wrong = 0, removed = 0;
        for (int step = 0; step < 20000; ++step) {
            if (step % 997 == 0) { // drop every item of one tag
                const uint32_t tag = uint32_t(rng() % 4);
                const size_t before = heap.size();
                heap.removeIf([&](const Item& it) { return it.tag == tag; });
                for (auto i = reference.begin(); i != reference.end();)
                    i = uint32_t(*i) == tag ? reference.erase(i) : std::next(i);
                ASSERT_EQ(heap.size(), reference.size());
                removed += before - heap.size();
                continue;
            }
            if (rng() % 3 == 0 || heap.empty()) {
                const Item it{rng() % 500, uint32_t(rng() % 4)};
                heap.push(it);
                reference.insert(it.rank());
                continue;
            }
            wrong += heap.top().rank() != *reference.begin();
            reference.erase(reference.begin());
            heap.pop(), ++popped;
        }
        while (!heap.empty()) {
            wrong += heap.top().rank() != *reference.begin();
            reference.erase(reference.begin());
            heap.pop(), ++popped;
        }
        EXPECT_TRUE(reference.empty()) << start;
        EXPECT_GT(removed, 0u) << start;
        EXPECT_EQ(wrong, 0u) << "of " << popped << " pops, starting from " << start;
    }
}
