// MemoryTest.cc - util::resizeInParallel does what resize does (the old elements kept, the new
// ones value-initialised), where it faults the new storage in on all threads first (a vector
// that grows past 4 MiB) and where it leaves the growing to resize (small, or within capacity).
#include "util/Memory.h"

#include <fluidsurf/Vec3.h>

#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <vector>

using namespace fluidsurf;

TEST(Memory, ResizeInParallelKeepsTheOldElementsAndZeroesTheNew)
{
    for (const size_t old : {size_t(0), size_t(1000), size_t(700000)})
        for (const size_t n : {size_t(10), size_t(500000), size_t(2000000)}) {
            std::vector<Vec3f> v(old);
            for (size_t i = 0; i < old; ++i)
                v[i] = Vec3f(float(i), -float(i), 0.5f);
            util::resizeInParallel(v, n);
            ASSERT_EQ(v.size(), n);
            for (size_t i = 0; i < n; ++i)
                ASSERT_EQ(v[i], i < old ? Vec3f(float(i), -float(i), 0.5f) : Vec3f(0, 0, 0))
                    << old << " -> " << n << " at " << i;
        }
    std::vector<std::array<uint32_t, 3>> t(3, {7, 8, 9});
    util::resizeInParallel(t, 1 << 20); // 12 MiB: grown on all threads
    EXPECT_EQ(t[2], (std::array<uint32_t, 3>{7, 8, 9}));
    EXPECT_EQ(t[3], (std::array<uint32_t, 3>{0, 0, 0}));
    EXPECT_EQ(t.back(), (std::array<uint32_t, 3>{0, 0, 0}));
}
