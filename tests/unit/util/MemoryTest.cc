// MemoryTest.cc - util::resizeInParallel does what resize does (the old elements kept, the new
// ones value-initialised), where it faults the new storage in on all threads first (a vector
// that grows past 4 MiB) and where it leaves the growing to resize (small, or within capacity);
// large arrays ask for huge pages on many threads only.
#include "util/Memory.h"

#include <fluidsurf/Vec3.h>

#include <gtest/gtest.h>
#include <tbb/task_arena.h>

#include <array>
#include <cstdint>
#include <cstdio>
#include <fstream>
#include <string>
#include <sys/mman.h>
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

namespace {

/// The VmFlags of the mapping that holds address a, from /proc/self/smaps ("" if none).
std::string vmFlagsAt(uintptr_t a)
{
    std::ifstream smaps("/proc/self/smaps");
    std::string line;
    bool inside = false;
    while (std::getline(smaps, line)) {
        unsigned long long lo = 0, hi = 0;
        if (std::sscanf(line.c_str(), "%llx-%llx ", &lo, &hi) == 2 && line.find(':') > 20)
            inside = a >= lo && a < hi;
        else if (inside && line.rfind("VmFlags:", 0) == 0)
            return line.substr(8) + " ";
    }
    return "";
}

bool transparentHugePagesOn()
{
    std::ifstream f("/sys/kernel/mm/transparent_hugepage/enabled");
    std::string mode;
    return std::getline(f, mode) && mode.find("[never]") == std::string::npos;
}

} // namespace

// The large arrays written whole ask for huge pages (the `hg` flag of their mapping) in a task
// arena of util::kHugePageThreads threads or more, and not in a smaller one; a range of less than
// two whole pieces never. (That one on a fresh mapping of its own: a small array may lie in heap
// memory that an earlier large one had asked for, and the flag stays with the memory.)
TEST(Memory, LargeArraysAskForHugePagesOnManyThreadsOnly)
{
    if (!transparentHugePagesOn()) GTEST_SKIP() << "no transparent huge pages on this kernel";
    constexpr size_t kFloats = size_t(16) << 20; // 64 MiB: a mapping of its own (glibc's default)
    auto advised = [](const void* p) {
        // a whole 2 MiB piece inside the array
        const uintptr_t at =
            (reinterpret_cast<uintptr_t>(p) + (size_t(4) << 20)) & ~uintptr_t(0xfff);
        return vmFlagsAt(at).find(" hg ") != std::string::npos;
    };
    for (const int threads : {2, util::kHugePageThreads - 1, util::kHugePageThreads, 16}) {
        tbb::task_arena arena(threads);
        arena.execute([&] {
            util::NoInitVector<float> big(kFloats);
            EXPECT_EQ(advised(big.data()), threads >= util::kHugePageThreads) << threads;
            std::vector<Vec3f> grown;
            util::resizeInParallel(grown, kFloats / 3);
            EXPECT_EQ(advised(grown.data()), threads >= util::kHugePageThreads) << threads;
            constexpr size_t kMapped = size_t(8) << 20, kPiece = size_t(2) << 20;
            void* fresh = ::mmap(nullptr, kMapped, PROT_READ | PROT_WRITE,
                                 MAP_PRIVATE | MAP_ANONYMOUS, -1, 0);
            ASSERT_NE(fresh, MAP_FAILED);
            const uintptr_t begin = reinterpret_cast<uintptr_t>(fresh);
            const uintptr_t first = (begin + kPiece - 1) & ~(kPiece - 1); // a piece's start
            auto hg = [](uintptr_t at) { return vmFlagsAt(at).find(" hg ") != std::string::npos; };
            util::adviseHugePages(first, 2 * kPiece - 1); // two pieces but for one byte
            EXPECT_FALSE(hg(first) || hg(first + kPiece)) << threads;
            util::adviseHugePages(first, 2 * kPiece); // and with it
            EXPECT_EQ(hg(first) && hg(first + kPiece), threads >= util::kHugePageThreads)
                << threads;
            ::munmap(fresh, kMapped);
        });
    }
}
