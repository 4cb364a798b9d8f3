// Temporaries.h - the hidden files AtomicFile writes before renaming them into place: their
// names, and the removal of those that killed runs left behind (internal; tests reach it).
#pragma once

#include <string>

namespace fluidsurf {
namespace io_internal {

/// True for a name AtomicFile makes (".fluidsurf-" + 12 of [0-9a-z], then the end or '.') or
/// made before (".fluidsurf-tmp-...").
bool isTemporaryName(const std::string& name);

/// ".fluidsurf-" + 12 random characters + the target's extension (".bgeo.gz", ".vdb"; none if
/// it is longer than 20 bytes): at most 43 bytes whatever the target's name.
std::string temporaryName(const std::string& targetName);

/// Remove the temporaries in folder that are provably stale: no process holds the lock a live
/// AtomicFile keeps on its temporary (flock, which holds across PID namespaces and, on NFS,
/// across hosts), and untouched for maxAgeSeconds (the guard for file systems whose locks do
/// not reach other hosts). Returns how many were removed.
int removeStaleTemporaries(const std::string& folder, double maxAgeSeconds);

} // namespace io_internal
} // namespace fluidsurf
