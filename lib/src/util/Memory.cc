// Memory.cc - huge pages for large arrays, faulting pages in on all threads (see Memory.h).
#include "util/Memory.h"

#include <tbb/task_arena.h>

#include <atomic>
#include <cerrno>
#include <sys/mman.h>
#include <unistd.h>

#ifndef MADV_POPULATE_WRITE
#define MADV_POPULATE_WRITE 23 // Linux 5.14 (older headers lack the name)
#endif

namespace fluidsurf {
namespace util {

void adviseHugePages(uintptr_t begin, size_t bytes)
{
    constexpr uintptr_t kHuge = uintptr_t(2) << 20;
    if (bytes < 2 * kHuge || tbb::this_task_arena::max_concurrency() < kHugePageThreads) return;
    const uintptr_t first = (begin + kHuge - 1) & ~(kHuge - 1),
                    last = (begin + bytes) & ~(kHuge - 1);
    // (a kernel without THP says EINVAL: the pages are then as they would have been)
    if (last > first) ::madvise(reinterpret_cast<void*>(first), last - first, MADV_HUGEPAGE);
}

void populateInParallel(uintptr_t begin, size_t bytes)
{
    adviseHugePages(begin, bytes);
    // a kernel without it says EINVAL once, and is not asked again
    static std::atomic<bool> unsupported{false};
    if (unsupported.load(std::memory_order_relaxed)) return;
    const uintptr_t page = uintptr_t(::sysconf(_SC_PAGESIZE));
    const uintptr_t first = (begin + page - 1) & ~(page - 1), last = (begin + bytes) & ~(page - 1);
    if (last <= first) return;
    constexpr uintptr_t kPiece = uintptr_t(2) << 20;
    tbb::parallel_for(size_t(0), size_t((last - first + kPiece - 1) / kPiece), [&](size_t i) {
        const uintptr_t from = first + i * kPiece, to = std::min(last, from + kPiece);
        if (::madvise(reinterpret_cast<void*>(from), to - from, MADV_POPULATE_WRITE) != 0 &&
            errno == EINVAL)
            unsupported.store(true, std::memory_order_relaxed);
    });
}

} // namespace util
} // namespace fluidsurf
