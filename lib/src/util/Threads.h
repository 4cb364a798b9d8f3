// Threads.h - run a pipeline under the Context's thread limit: a TBB arena of that many threads
// (all cores for 0). Local to the call, unlike tbb::global_control, so two contexts with other
// limits can run side by side; results do not depend on the count (DESIGN.md, "Backends").
#pragma once

#include <fluidsurf/Context.h>

#include <tbb/task_arena.h>

namespace fluidsurf {
namespace util {

template <typename F> auto withThreads(const Context& ctx, F&& f) -> decltype(f())
{
    if (ctx.threads() <= 0) return f();
    tbb::task_arena arena(ctx.threads());
    return arena.execute(std::forward<F>(f));
}

} // namespace util
} // namespace fluidsurf
