// Sequence.cc - runFrameStages as a TBB pipeline of three filters (read and write serial and in
// order; make too, up to 3 slots); its tokens are the frames in flight.
//
// No exception leaves a filter. One that did would cancel the pipeline's task group, and with it
// every parallel loop that a stage under way runs inside (they inherit the group): those loops
// would stop early without a word, and their stage would go on with half its work done. So a
// stage's exception is kept, later frames are passed over, and it is rethrown at the end.
#include <fluidsurf/Sequence.h>

#include <tbb/parallel_pipeline.h>

#include <algorithm>
#include <atomic>
#include <exception>
#include <mutex>

namespace fluidsurf {

void runFrameStages(size_t count, const FrameStages& stages, size_t slots)
{
    if (count == 0) return;
    slots = std::max<size_t>(1, slots);
    std::atomic<bool> failed{false};
    std::exception_ptr first;
    std::mutex firstMutex;
    auto run = [&](const std::function<void(size_t, size_t)>& stage, size_t k) {
        if (failed.load()) return;
        try {
            stage(k, k % slots);
        } catch (...) {
            std::lock_guard<std::mutex> lock(firstMutex);
            if (!first) first = std::current_exception();
            failed.store(true);
        }
    };
    size_t next = 0;
    tbb::parallel_pipeline(
        slots, tbb::make_filter<void, size_t>(tbb::filter_mode::serial_in_order,
                                              [&](tbb::flow_control& fc) -> size_t {
                                                  if (next == count || failed.load()) {
                                                      fc.stop();
                                                      return 0;
                                                  }
                                                  const size_t k = next++;
                                                  run(stages.read, k);
                                                  return k;
                                              }) &
                   tbb::make_filter<size_t, size_t>(slots > 3 ? tbb::filter_mode::parallel
                                                              : tbb::filter_mode::serial_in_order,
                                                    [&](size_t k) {
                                                        run(stages.make, k);
                                                        return k;
                                                    }) &
                   tbb::make_filter<size_t, void>(tbb::filter_mode::serial_in_order,
                                                  [&](size_t k) { run(stages.write, k); }));
    if (first) std::rethrow_exception(first);
}

} // namespace fluidsurf
