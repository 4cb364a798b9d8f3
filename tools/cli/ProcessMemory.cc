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

#include <tbb/info.h>

#include <csignal>
#include <pthread.h>

#include <cstdint>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <string>

namespace fluidsurf {
namespace cli {

namespace {

char** gArgv = nullptr;     ///< main's, for useHugePagesFor
bool gStartedAgain = false; ///< by useHugePagesFor

/// Holds GLIBC_TUNABLES as the user had it ("-" for unset) in a process that useHugePagesFor
/// started again.
constexpr const char* kTunablesBefore = "FLUIDSURF_TUNABLES_BEFORE";

/// Whether the kernel gives transparent huge pages to memory that asks for them (its setting
/// "always" or "madvise", not "never").
bool hugePagesOnRequest()
{
    std::ifstream in("/sys/kernel/mm/transparent_hugepage/enabled");
    std::string setting;
    std::getline(in, setting);
    return setting.find("[always]") != std::string::npos ||
           setting.find("[madvise]") != std::string::npos;
}

void setTunables(const char* value)
{
    if (value)
        setenv("GLIBC_TUNABLES", value, 1);
    else
        unsetenv("GLIBC_TUNABLES");
}

} // namespace

// Why huge pages: a frame's stages fault in their arrays page by page, and on a virtual machine
// each fault is dear: the 1.7M-particle frame took 65,000 faults and 0.7 s of system time of its
// 6.4 CPU-seconds on 2 cores, 3.43-3.54 s a run; with the heap on 2 MB pages, 17,600 faults and
// 3.04-3.08 s, the same bytes out (the 400k-particle frame 1.29 -> 1.17 s, hilbert's 47k 0.50 ->
// 0.46 s). glibc reads the tunable only as a process starts, so the process starts again, and
// a start costs 0.08-0.1 s here (the loader binding OpenVDB's 63,000 relocations): paid back
// from about 400k particles, which is why only runs that read kHugePagesFrom or more do it
// (12 MiB: 1M particles as .xyz, 300k as .vtk; a sequence counts all its frames). On 8 threads
// and more the library asks for huge pages for its big arrays itself (util::adviseHugePages),
// and the start again is a loss: an H200 host's 16 threads, 5 runs alternating, the 1.7M frame
// 0.844 -> 0.878 s (CUDA 1.120 -> 1.098 s), the 13.1M drop 1.983 -> 1.960 s (CUDA 2.068 ->
// 2.139 s), medians; so only runs on fewer threads start again.
void useHugePagesFor(uint64_t inputBytes, int threads, bool (*interrupted)())
{
#ifdef __GLIBC__
    const char* choice = std::getenv("FLUIDSURF_HUGE_PAGES"); // "0" never, "1" always
    const bool always = choice && std::strcmp(choice, "1") == 0;
    const int used = threads > 0 ? threads : tbb::info::default_concurrency();
    const bool worth = inputBytes >= kHugePagesFrom && used < kHugePagesBelowThreads;
    if ((choice && std::strcmp(choice, "0") == 0) || !(worth || always) || !gArgv) return;
    if (gStartedAgain) return;
    const char* set = std::getenv("GLIBC_TUNABLES");
    if (set && std::strstr(set, "glibc.malloc.hugetlb")) return; // the user's choice
    if (!hugePagesOnRequest()) return;
    // (a copy: setenv may leave getenv's pointer stale)
    const std::string tunables = set ? set : "";
    const std::string with = tunables.empty() ? std::string("glibc.malloc.hugetlb=1")
                                              : tunables + ":glibc.malloc.hugetlb=1";
    // Ctrl-C and SIGTERM blocked across the start: one that comes then waits, pending, for the
    // new process's handler (installInterruptHandler unblocks them) instead of ending it
    // without a word or being lost with this process's flag; one that came already stops the
    // run here, as it is.
    sigset_t stops, before;
    sigemptyset(&stops), sigaddset(&stops, SIGINT), sigaddset(&stops, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &stops, &before);
    if (interrupted && interrupted()) {
        pthread_sigmask(SIG_SETMASK, &before, nullptr);
        return;
    }
    setenv(kTunablesBefore, set ? tunables.c_str() : "-", 1);
    setTunables(with.c_str());
    execv("/proc/self/exe", gArgv);
    unsetenv(kTunablesBefore); // not started again (no /proc): on as it is
    setTunables(set ? tunables.c_str() : nullptr);
    pthread_sigmask(SIG_SETMASK, &before, nullptr);
#else
    (void)inputBytes, (void)threads, (void)interrupted;
#endif
}

void setUpProcessMemory(char** argv)
{
    gArgv = argv;
    // started again by useHugePagesFor: the environment as the user had it, for children
    if (const char* before = std::getenv(kTunablesBefore)) {
        gStartedAgain = true;
        setTunables(std::strcmp(before, "-") == 0 ? nullptr : before);
        unsetenv(kTunablesBefore);
    }
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
