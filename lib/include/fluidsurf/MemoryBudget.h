// MemoryBudget.h - the most memory one request may take. Stages and readers estimate what a
// large structure will need before they build it and refuse past the budget, with the estimate:
// an oversized request (a voxel far too small for the frame, a file whose header promises a
// billion points, a level set of huge active tiles) fails at once instead of being killed by the
// kernel, or taking the machine down with it (issue 63). A Context may set its own
// (Context::setMemoryBudget); readers, which have none, use the process's.
#pragma once

#include <cstddef>
#include <string>

namespace fluidsurf {

/// The process's budget in bytes: what setProcessMemoryBudget set, else 80% of the physical
/// memory.
size_t processMemoryBudget();
/// 0 goes back to the default. The CLI's --max-memory.
void setProcessMemoryBudget(size_t bytes);

/// ValueError "WHAT needs about N MiB, more than the memory budget of M MiB (...)" when bytes
/// passes budget (0: processMemoryBudget()).
void requireMemory(double bytes, const std::string& what, size_t budget = 0);

} // namespace fluidsurf
