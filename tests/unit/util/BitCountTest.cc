// BitCountTest.cc - util::bitCount3 against the compiler's popcount, word by word.
#include "util/BitCount.h"

#include <gtest/gtest.h>

#include <cstdint>

using namespace fluidsurf;

TEST(BitCount, ThreeWordsCountAsTheirBitsOneByOne)
{
    const uint64_t edges[] = {0,
                              ~uint64_t(0),
                              1,
                              uint64_t(1) << 63,
                              0x5555555555555555ull,
                              0xAAAAAAAAAAAAAAAAull,
                              0x0F0F0F0F0F0F0F0Full};
    for (uint64_t a : edges)
        for (uint64_t b : edges)
            for (uint64_t c : edges)
                ASSERT_EQ(util::bitCount3(a, b, c),
                          uint32_t(__builtin_popcountll(a) + __builtin_popcountll(b) +
                                   __builtin_popcountll(c)));
    uint64_t seed = 7; // a 64-bit LCG: the same words on every platform
    auto next = [&] { return seed = seed * 6364136223846793005ull + 1442695040888963407ull; };
    for (int i = 0; i < 100000; ++i) {
        // sparse and dense words too, as the crossing-edge words of a leaf are
        const uint64_t a = next(), b = next() & next() & next(), c = next() | next();
        ASSERT_EQ(
            util::bitCount3(a, b, c),
            uint32_t(__builtin_popcountll(a) + __builtin_popcountll(b) + __builtin_popcountll(c)))
            << a << " " << b << " " << c;
    }
}
