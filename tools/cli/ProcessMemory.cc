// ProcessMemory.cc - see ProcessMemory.h.
//
// Why release the loader's tables: Debian's libopenvdb exports every template instance it
// holds, and its dynamic symbols and their names fill a 26 MB segment. Binding the 60,000
// relocations at start-up reads names all over it, and the kernel maps the pages around each
// one read, so the whole segment stays resident: 26 of the 37 MB a bare `fluidsurf --version`
// holds, more than all the work on a small frame. After start-up only a function's first call
// reads them again, a few pages at a time.
#include "ProcessMemory.h"

#ifdef __GLIBC__
#include <malloc.h>
#endif

#ifdef __linux__
#include <elf.h>
#include <link.h>
#include <sys/mman.h>
#include <unistd.h>
#endif

#include <cstdint>

namespace fluidsurf {
namespace cli {

void setUpProcessMemory()
{
#ifdef __GLIBC__
    // Memory a stage frees is kept for the next one: no array gets a mapping of its own
    // (unmapped when freed), and free() does not trim the heap (the stages' malloc_trim calls,
    // util::returnFreedMemory, still do). Each fresh page costs a fault and a zeroed page, and
    // 16 threads faulting at once contend in the kernel: with arrays of 1 MiB and more mapped
    // whole, as this was, the 13.1M-particle drop took 1.63 s and 486k faults on an H200
    // host's 16 threads, 1.48 s and 304k now. The cost is the heap's holes staying resident:
    // peak 604 -> 627 MB there and 196 -> 206 MB on the 1.7M-particle frame (about the same
    // on 2 cores), more in a sequence with frames in flight (587 -> 698-781 MB for that frame
    // x 12; --in-flight 1 is the low-memory way). Without the malloc_trim calls too, peaks
    // grew by a third for a few percent. (BENCHMARKS.md, issue 16.)
    mallopt(M_MMAP_THRESHOLD, 1 << 30);
    mallopt(M_TRIM_THRESHOLD, 1 << 30);
#endif
    releaseLoaderTables();
}

#ifdef __linux__
namespace {

/// The object's symbol table address, or 0 if it has none or has text relocations (whose
/// read-only pages the loader wrote: dropping them would undo its writes).
uintptr_t symbolTable(const dl_phdr_info& info)
{
    uintptr_t symtab = 0;
    for (int i = 0; i < info.dlpi_phnum; ++i) {
        if (info.dlpi_phdr[i].p_type != PT_DYNAMIC) continue;
        for (auto* d =
                 reinterpret_cast<const ElfW(Dyn)*>(info.dlpi_addr + info.dlpi_phdr[i].p_vaddr);
             d->d_tag != DT_NULL; ++d) {
            if (d->d_tag == DT_TEXTREL) return 0;
            if (d->d_tag == DT_FLAGS && (d->d_un.d_val & DF_TEXTREL)) return 0;
            if (d->d_tag == DT_SYMTAB) symtab = d->d_un.d_ptr;
        }
    }
    return symtab;
}

/// Whether the segment [begin, end) holds the symbol table: glibc has moved the address by the
/// object's base where .dynamic is writable, not elsewhere (the vDSO's), so either may be seen.
bool holds(uintptr_t begin, uintptr_t end, uintptr_t symtab, uintptr_t base)
{
    return (symtab >= begin && symtab < end) || (symtab + base >= begin && symtab + base < end);
}

int releaseObject(dl_phdr_info* info, size_t, void* advised)
{
    const uintptr_t symtab = symbolTable(*info);
    if (symtab == 0) return 0;
    const auto page = uintptr_t(sysconf(_SC_PAGESIZE));
    for (int i = 0; i < info->dlpi_phnum; ++i) {
        const ElfW(Phdr)& p = info->dlpi_phdr[i];
        // read-only, not executable, not the relocated-then-protected segment (RELRO is
        // PF_R | PF_W in its header): written by no one, so its pages are the file's
        if (p.p_type != PT_LOAD || p.p_flags != PF_R) continue;
        const uintptr_t begin = info->dlpi_addr + p.p_vaddr, end = begin + p.p_memsz;
        if (!holds(begin, end, symtab, info->dlpi_addr)) continue;
        // whole pages inside the segment only: a page it shares with the next one stays
        const uintptr_t from = (begin + page - 1) & ~(page - 1), to = end & ~(page - 1);
        if (to > from && madvise(reinterpret_cast<void*>(from), to - from, MADV_DONTNEED) == 0)
            *static_cast<size_t*>(advised) += to - from;
    }
    return 0;
}

} // namespace

size_t releaseLoaderTables()
{
    size_t advised = 0;
    dl_iterate_phdr(releaseObject, &advised);
    return advised;
}
#else
size_t releaseLoaderTables()
{
    return 0;
}
#endif

} // namespace cli
} // namespace fluidsurf
