// AtomicFile.h - write-to-temporary-then-rename, so a failed or interrupted run never leaves a
// half-written output and never destroys an existing file (DESIGN.md, "Errors").
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

namespace fluidsurf {
namespace io {

/// A temporary beside the target, ".fs-RANDOM.EXT" (EXT the target's extension, so that the
/// format is still known from the name; short, so that any valid target name has a valid
/// temporary), created with O_EXCL and locked (flock) for as long as this object lives.
/// commit() syncs it and renames it over the target; the destructor removes it if commit() was
/// never reached (an exception on the way). An existing target that is not a regular file (a
/// folder, FIFO, device) is refused; a symbolic link to a file is followed, so the link stays
/// and the file it names is replaced. Temporaries that killed runs left behind are removed when
/// they are provably stale: unlocked and untouched for an hour (never by PID, which means
/// nothing in another PID namespace or on another host). Every error names the target.
///
/// A target that is itself the temporary of an OutputGroup (its add()) is written in place:
/// no second temporary, and errors name the group's target, not the hidden name.
class AtomicFile
{
public:
    explicit AtomicFile(const std::string& target);
    ~AtomicFile();
    AtomicFile(const AtomicFile&) = delete;
    AtomicFile& operator=(const AtomicFile&) = delete;

    const std::string& tempPath() const { return mTemp; }
    /// The path renamed over at commit (a followed link's file).
    const std::string& target() const { return mTarget; }
    /// The name for messages: the path the user gave.
    const std::string& name() const { return mName; }
    /// The temporary, open for writing (O_WRONLY), owned here.
    int fd() const { return mFd; }
    /// fsync, then rename over the target. OutputError naming the target on failure (the
    /// temporary is removed and an older target kept).
    void commit();

private:
    std::string mName, mTarget, mTemp;
    int mFd = -1;
    bool mCommitted = false, mInGroup = false;
};

/// Removes the temporary of every live AtomicFile of this process. For a process that is about
/// to end without unwinding (_exit after a signal whose run did not stop in time): nothing
/// partial is left behind. Thread-safe; not for signal handlers.
void removeLiveTemporaries();

/// OutputError unless an AtomicFile for target could be made: a path that names a file, in a
/// folder that exists and this process may write into, and that is not an existing folder,
/// FIFO, socket or device. For front ends that check every output before the work, so that a
/// typo in a folder name costs no minutes of computing first.
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
    ~OutputGroup();
    OutputGroup(const OutputGroup&) = delete;
    OutputGroup& operator=(const OutputGroup&) = delete;
    /// The temporary path to write target's content to (same folder, same extension). Writers
    /// given it write into it in place and name target in their errors.
    std::string add(const std::string& target);
    void commit();

private:
    std::vector<std::unique_ptr<AtomicFile>> mFiles;
};

} // namespace io
} // namespace fluidsurf
