// Frames.h - turning a path (or pattern) and --frames into the list of frame numbers to process.
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/FramePattern.h>

#include <cstdint>
#include <string>
#include <vector>

namespace fluidsurf {
namespace cli {

struct FrameJob
{
    std::string input, output;
    int frame = -1; ///< -1 for a single file
};

/// Frame jobs for an input (pattern or file) and an optional output pattern. A sequence
/// without --frames takes the frames that exist on disk. ValueError when nothing matches or
/// the output is not a pattern while the input is.
std::vector<FrameJob> planFrames(const std::string& input, const std::string& output,
                                 const std::string& range);

/// planFrames for level-set outputs: ValueError "<what> 'NAME' must end in .vdb" otherwise.
std::vector<FrameJob> planVdbFrames(const std::string& input, const std::string& output,
                                    const std::string& range, const std::string& what);

/// ValueError, before any work, when an output path of the run is one of its inputs (the same
/// file by device and inode, or by real path for outputs that do not exist yet; every frame of
/// a sequence against every input frame), or when two outputs are the same file. Naming both.
void refuseOverwritingInputs(const std::vector<std::string>& inputs,
                             const std::vector<std::string>& outputs);

/// OutputError, before any work, when an output's folder is missing or not writable (the
/// error its writing would end with, minutes of computing later).
void refuseUnwritableOutputs(const std::vector<std::string>& outputs);

/// Both checks above, before any work, over outputs and the --stats file (when given): no file
/// a run writes is one of its inputs or another of its outputs, and every one can be written.
void checkRunFiles(const std::vector<std::string>& inputs, std::vector<std::string> outputs,
                   const std::string& stats = std::string());

/// The bytes of the input files of jobs[i] for i in picked (those that can be read).
uint64_t inputBytes(const std::vector<FrameJob>& jobs, const std::vector<size_t>& picked);

/// Whether a particle run on ctx should start making the CUDA context while its first frame is
/// read (prepareDevice): always for Device::Cuda, never for Cpu, and for Auto unless no frame of
/// jobs[i], i in todo, can reach the GPU's threshold (autoGpuParticles at ctx.runThreads(), the
/// largest frame's particles times the frames): a process that makes a context it does not use
/// pays for it at exit (one 1M frame a process on the H200 host: 0.48 s with --device auto
/// against 0.37 s on the CPU). A file holds at most a particle per 6 bytes (.npy of half
/// floats); compressed ones (.gz, .vtu, .vtp, .vdb) could hold any number, so those are prepared.
bool worthPreparingDevice(const Context& ctx, const std::vector<FrameJob>& jobs,
                          const std::vector<size_t>& todo);

/// The inputs and outputs of frame jobs, for refuseOverwritingInputs.
std::vector<std::string> inputsOf(const std::vector<FrameJob>& jobs);
std::vector<std::string> outputsOf(const std::vector<FrameJob>& jobs);

} // namespace cli
} // namespace fluidsurf
