// ProcessMemory.h - the command line's process-wide memory settings, made once at the start
// of main (the library leaves the process's allocator and mappings to its host).
#pragma once

#include <cstddef>

namespace fluidsurf {
namespace cli {

/// glibc's heap kept for reuse (no large array mapped on its own, no trimming on free), and
/// releaseLoaderTables() (see ProcessMemory.cc).
void setUpProcessMemory();

/// Drops from the process the resident pages of each loaded object's symbol tables (the
/// read-only segment holding its dynamic symbols, their names and relocations), which the
/// dynamic loader read at start-up and which are needed again only to bind a function on its
/// first call. They are clean pages of the file: one that is needed again is read back from
/// the page cache. Objects with text relocations are left alone. Returns the bytes advised
/// (resident or not); 0 where the system is not Linux.
size_t releaseLoaderTables();

} // namespace cli
} // namespace fluidsurf
