// Sequence.h - a sequence's frames through their three stages at once: while frame k is made,
// frame k+1 is read and frame k-1 written. Reading and writing are mostly serial (one file, one
// thread), and a reconstruction has serial steps of its own; overlapping them keeps the cores
// busy between frames. One process (one CUDA context) serves the whole sequence.
//
//   std::vector<Frame> slots(3);                       // the caller's data per frame in flight
//   fluidsurf::FrameStages stages;
//   stages.read = [&](size_t k, size_t s) { slots[s].particles = read(k); };
//   stages.make = [&](size_t k, size_t s) { slots[s].result = reconstruct(...); };
//   stages.write = [&](size_t k, size_t s) { write(k, slots[s].result); slots[s] = {}; };
//   fluidsurf::runFrameStages(frames, stages, slots.size());
#pragma once

#include <cstddef>
#include <functional>

namespace fluidsurf {

/// A frame's three stages. Each is called with the frame's position k in the run (0, 1, ...)
/// and its slot, k % slots: the caller keeps a frame's data in its slot from read to write.
struct FrameStages
{
    std::function<void(size_t k, size_t slot)> read, make, write;
};

/// Runs frames 0..count-1 through read, make and write, at most `slots` frames from the start
/// of their read to the end of their write (so slot k % slots is free when frame k is read).
/// Read and write take one frame at a time, in order; make does too with up to 3 slots, and
/// with more it may run on several frames at once (for many cores that one frame leaves partly
/// idle). Different stages run at once on different frames; slots = 1 runs one frame after the
/// other. A stage may use the parallel algorithms (TBB) inside; the stages run on the same
/// threads.
///
/// An exception from a stage stops the run: stages under way finish their frame, no frame
/// starts, and the first exception is rethrown here. A caller that wants frames to fail alone
/// catches in its stages and reports in write, which sees the frames in order.
void runFrameStages(size_t count, const FrameStages& stages, size_t slots = 3);

} // namespace fluidsurf
