// AtomicFile.h - write-to-temporary-then-rename, so a failed or interrupted run never leaves a
// half-written output and never destroys an existing file (DESIGN.md, "Errors").
#pragma once

#include <cstdint>
#include <string>

namespace fluidsurf {
namespace io {

/// A temporary path in the target's folder; commit() renames it over the target, the
/// destructor removes it if commit() was never reached (an exception on the way).
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

/// Write bytes to path atomically; OutputError on failure.
void writeFileAtomic(const std::string& path, const void* data, size_t size);

} // namespace io
} // namespace fluidsurf
