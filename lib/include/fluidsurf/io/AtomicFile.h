// AtomicFile.h - write-to-temporary-then-rename, so a failed or interrupted run never leaves a
// half-written output and never destroys an existing file (DESIGN.md, "Errors").
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace fluidsurf {
namespace io {

/// A temporary path in the target's folder, ".fluidsurf-tmp-PID-N.NAME" (the target's name last,
/// so its extension still says the format); commit() renames it over the target, the destructor
/// removes it if commit() was never reached (an exception on the way). Temporaries that a killed
/// run left in the folder (their PID no longer runs) are removed when the next one is made.
class AtomicFile
{
public:
    explicit AtomicFile(const std::string& target);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    const std::string& tempPath() const { return mTemp; }
    const std::string& target() const { return mTarget; }
    void commit();

private:
    std::string mTarget, mTemp;
    bool mCommitted = false;
};

/// OutputError unless an AtomicFile for target could be made: a path that names a file, in a
/// folder that exists and this process may write into. For front ends that check every output
/// before the work, so that a typo in a folder name costs no minutes of computing first.
void requireWritableFolder(const std::string& target);

/// Write bytes to path atomically; OutputError on failure.
void writeFileAtomic(const std::string& path, const void* data, size_t size);

/// Outputs that appear together or not at all (the level set and the mesh of one frame): write
/// each to the path add() returns, then commit() moves them all into place, one rename each,
/// after every write succeeded. Destroyed without commit(), it removes what was written.
class OutputGroup
{
public:
    OutputGroup() = default;
    OutputGroup(const OutputGroup&) = delete;
    OutputGroup& operator=(const OutputGroup&) = delete;
    /// The temporary path to write target's content to (same folder, same extension).
    std::string add(const std::string& target);
    void commit();

private:
    std::vector<std::unique_ptr<AtomicFile>> mFiles;
};

} // namespace io
} // namespace fluidsurf
