// Memory.h - handing the heap's free pages back between the steps of a stage.
//
// Why: an array of a MiB or more that finds a free block in the heap (the holes the level
// set's leaves left when it went, say) is carved from it rather than mapped, and when it is
// freed, its pages stay resident in the heap until something trims them. Step after step, those
// pages added 30-50 MB to decimation's peak on the 1.7M-particle frame. A trim costs about half
// a millisecond here.
#pragma once

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

} // namespace util
} // namespace fluidsurf
