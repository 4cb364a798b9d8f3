// ProcessMemory.h - the command line's process-wide memory settings, made once at the start
// of main (the library leaves the process's allocator and mappings to its host).
#pragma once

#include <cstddef>
#include <cstdint>

namespace fluidsurf {
namespace cli {

/// glibc's heap kept for reuse (no large array mapped on its own, no trimming on free), and
/// releaseLoaderTables() (see ProcessMemory.cc). argv: main's, for useHugePagesFor.
void setUpProcessMemory(char** argv);

/// Input a run reads from which its heap goes on huge pages (useHugePagesFor).
constexpr uint64_t kHugePagesFrom = uint64_t(12) << 20;
/// Threads from which it does not: the library's own huge pages take over there (the value of
/// util::kHugePageThreads, lib/src/util/Memory.h, which the command line does not include).
constexpr int kHugePagesBelowThreads = 8;

/// With inputBytes >= kHugePagesFrom (the files of the frames this run will read) and fewer
/// than kHugePagesBelowThreads threads (`threads`, -j; 0 for all the cores TBB sees), starts the
/// process again, the same arguments, with glibc's heap on transparent huge pages (the tunable
/// glibc.malloc.hugetlb=1); call it before any output and before any thread of the run's own.
/// FLUIDSURF_HUGE_PAGES=1 does it whatever the input, =0 never. Not when the kernel gives no huge
/// pages, or when GLIBC_TUNABLES names the tunable already. The process started again sees
/// GLIBC_TUNABLES as the user had it (its children do not inherit the tunable). Why and when:
/// ProcessMemory.cc.
/// interrupted: whether Ctrl-C or SIGTERM came already (the run then goes on as it is, to stop).
void useHugePagesFor(uint64_t inputBytes, int threads, bool (*interrupted)() = nullptr);

/// Drops from the process the resident pages of each loaded object's symbol tables (the
/// read-only segment holding its dynamic symbols, their names and relocations), which the
/// dynamic loader read at start-up and which are needed again only to bind a function on its
/// first call. They are clean pages of the file: one that is needed again is read back from
/// the page cache. Objects with text relocations are left alone. Returns the bytes advised
/// (resident or not); 0 where the system is not Linux.
size_t releaseLoaderTables();

} // namespace cli
} // namespace fluidsurf
