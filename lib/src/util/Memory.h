// Memory.h - handing the heap's free pages back between the steps of a stage.
//
// Why: an array of a MiB or more that finds a free block in the heap (the holes the level
// set's leaves left when it went, say) is carved from it rather than mapped, and when it is
// freed, its pages stay resident in the heap until something trims them. Step after step, those
// pages added 30-50 MB to decimation's peak on the 1.7M-particle frame. A trim costs about half
// a millisecond here.
#pragma once

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <memory> // (first: a C++ header defines __GLIBC__ for the test below)
#include <new>
#include <type_traits>
#include <utility>
#include <vector>

#ifdef __GLIBC__
#include <malloc.h>
#endif

namespace fluidsurf {
namespace util {

/// Returns the heap's free pages to the system (glibc's malloc_trim; nothing elsewhere).
inline void returnFreedMemory()
{
#ifdef __GLIBC__
    malloc_trim(0);
#endif
}

/// Threads from which adviseHugePages asks for huge pages (see there).
constexpr int kHugePageThreads = 8;

/// Asks the kernel to back the whole 2 MiB pieces of [begin, begin + bytes) with transparent
/// huge pages (MADV_HUGEPAGE; honoured where THP is in its `madvise` or `always` mode), for an
/// array of 4 MiB or more that is written whole, and only while the current task arena has
/// kHugePageThreads threads or more; otherwise nothing. Why: a fresh 4 KiB page costs a fault,
/// and 16 threads faulting at once contend in the kernel; with 2 MiB pages the 13.1M-particle
/// drop took 277k -> 70k faults on an H100 host's 16 threads, 1.74 -> 1.67 s whole (medians of
/// 5), and the 1.7M-particle frame 0.89 -> 0.79 s. Why not on fewer threads: on the 2-core VM
/// the kernel zeroed huge pages at several times the cost per byte (a VM's fresh memory), and
/// the drop took 4.9 -> 5.2 s. Pages only: it reads and writes no object. (BENCHMARKS.md.)
void adviseHugePages(uintptr_t begin, size_t bytes);

/// An allocator whose vectors leave new elements of a trivial type uninitialised (resize(n),
/// vector(n)): an array of hundreds of MB is then first touched by the parallel loop that fills
/// it, instead of zeroed by one thread first (0.07 s for the 13.1M particles' sort handles).
template <typename T> struct NoInitAllocator : std::allocator<T>
{
    template <typename U> struct rebind
    {
        using other = NoInitAllocator<U>;
    };
    NoInitAllocator() = default;
    template <typename U> NoInitAllocator(const NoInitAllocator<U>&) noexcept {}
    /// std::allocator's, the storage of a large array advised to huge pages (adviseHugePages):
    /// these arrays are the ones written whole by parallel loops.
    T* allocate(size_t n)
    {
        T* p = std::allocator<T>::allocate(n);
        adviseHugePages(reinterpret_cast<uintptr_t>(p), n * sizeof(T));
        return p;
    }
    /// Nothing at all for a plain type of bytes (Vec3f too, whose default constructor would
    /// zero it): the code that asked for the elements writes each before it reads it.
    template <typename U> void construct(U* p) noexcept
    {
        if constexpr (!(std::is_trivially_copyable_v<U> && std::is_trivially_destructible_v<U>))
            ::new (static_cast<void*>(p)) U;
    }
    template <typename U, typename... Args> void construct(U* p, Args&&... args)
    {
        ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
    }
};

/// A vector whose new elements are not zeroed (see NoInitAllocator): for arrays of hundreds of
/// MB that parallel loops fill whole, which one thread would otherwise zero first.
template <typename T> using NoInitVector = std::vector<T, NoInitAllocator<T>>;

/// Every element of v set to value, on all threads: a NoInitVector's pages are first touched
/// here, not by one thread zeroing them.
template <typename Vector, typename T> void fillInParallel(Vector& v, const T& value)
{
    tbb::parallel_for(
        tbb::blocked_range<size_t>(0, v.size(), 1 << 14), [&](const tbb::blocked_range<size_t>& r) {
            std::fill(v.begin() + ptrdiff_t(r.begin()), v.begin() + ptrdiff_t(r.end()), value);
        });
}

/// Faults in the pages of [begin, begin + bytes) on all threads, a 2 MiB piece each (Linux's
/// MADV_POPULATE_WRITE, since 5.14; where the kernel lacks it, nothing, and the pages fault in
/// where they are first written), advised to huge pages first (adviseHugePages). Pages only:
/// it reads and writes no object.
void populateInParallel(uintptr_t begin, size_t bytes);

/// v.resize(n) (new elements value-initialised, as resize does), the pages of its new storage
/// faulted in on all threads first. Why: a std::vector that grows by hundreds of MB zeroes its
/// new elements on one thread, and the page faults of that first touch, not the zeros, are its
/// cost (157 MB of positions: 70 ms on one thread here, 34 ms with the faults on two; more so
/// on sixteen). For the vectors with the standard allocator: the public types' (ParticleSet,
/// TriangleMesh) and the few of the library's own that are handed to code taking those; its
/// other large arrays are NoInitVectors, first touched on all threads.
template <typename Vector> void resizeInParallel(Vector& v, size_t n)
{
    using T = typename Vector::value_type;
    constexpr size_t kWorthIt = size_t(4) << 20; // below this, one thread is as quick
    if (n > v.capacity() && n * sizeof(T) >= kWorthIt) {
        Vector grown;
        grown.reserve(n);
        populateInParallel(reinterpret_cast<uintptr_t>(grown.data()), n * sizeof(T));
        grown.assign(std::make_move_iterator(v.begin()), std::make_move_iterator(v.end()));
        v.swap(grown);
    }
    v.resize(n);
}

} // namespace util
} // namespace fluidsurf
