// AtomicFile.cc - temporary file + fsync + rename(2).
#include <fluidsurf/Error.h>
#include <fluidsurf/io/AtomicFile.h>

#include "io/StreamFile.h"

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <unistd.h>

#include <cstdlib>
#include <mutex>
#include <set>
#include <utility>

namespace fluidsurf {
namespace io {

namespace {
constexpr const char* kTempPrefix = ".fluidsurf-tmp-";

std::string folderOf(const std::string& path)
{
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? std::string(".") : path.substr(0, slash + 1);
}

/// Temporaries of runs that were killed (SIGKILL, power loss) before their destructors ran:
/// ".fluidsurf-tmp-PID-..." whose PID is no longer a running process. Once per folder and
/// process.
void removeStaleTemporaries(const std::string& folder)
{
    static std::mutex mutex;
    static std::set<std::string> done;
    {
        std::lock_guard<std::mutex> lock(mutex);
        if (!done.insert(folder).second) return;
    }
    DIR* dir = ::opendir(folder.c_str());
    if (!dir) return;
    const size_t prefix = std::strlen(kTempPrefix);
    while (const dirent* entry = ::readdir(dir)) {
        const std::string name = entry->d_name;
        if (name.compare(0, prefix, kTempPrefix) != 0) continue;
        char* end = nullptr;
        const long pid = std::strtol(name.c_str() + prefix, &end, 10);
        if (pid <= 0 || !end || *end != '-') continue;
        if (::kill(pid_t(pid), 0) == 0 || errno != ESRCH) continue; // alive, or not ours to judge
        const std::string path = folder + (folder.back() == '/' ? "" : "/") + name;
        ::unlink(path.c_str());
    }
    ::closedir(dir);
}
} // namespace

void requireWritableFolder(const std::string& target)
{
    if (target.empty()) throw OutputError("empty output path");
    if (target.back() == '/') throw OutputError(target + ": output path names a folder");
    if (::access(folderOf(target).c_str(), W_OK) != 0)
        throw OutputError(target + ": cannot write into folder '" + folderOf(target) +
                          "': " + std::strerror(errno));
}

AtomicFile::AtomicFile(const std::string& target) : mTarget(target)
{
    requireWritableFolder(target);
    static std::atomic<unsigned> counter{0};
    // Hidden name in the same folder: rename() stays atomic (same file system).
    const size_t slash = target.find_last_of('/');
    const std::string base = slash == std::string::npos ? target : target.substr(slash + 1);
    const std::string dir =
        slash == std::string::npos ? std::string() : target.substr(0, slash + 1);
    removeStaleTemporaries(folderOf(target));
    mTemp = dir + kTempPrefix + std::to_string(::getpid()) + "-" + std::to_string(counter++) + "." +
            base;
}

AtomicFile::~AtomicFile()
{
    if (!mCommitted) ::unlink(mTemp.c_str());
}

void AtomicFile::commit()
{
    int fd = ::open(mTemp.c_str(), O_RDONLY);
    if (fd >= 0) {
        // a failed fsync (EIO, ENOSPC, EDQUOT) means bytes may not have reached the disk: no
        // rename over an older good file then (file systems that cannot sync say EINVAL)
        const bool synced = ::fsync(fd) == 0 || errno == EINVAL || errno == EROFS;
        const int err = errno;
        ::close(fd);
        if (!synced)
            throw OutputError(mTarget + ": write failed at the end: " + std::strerror(err));
    }
    if (::rename(mTemp.c_str(), mTarget.c_str()) != 0)
        throw OutputError(mTarget +
                          ": cannot move the finished file into place: " + std::strerror(errno));
    mCommitted = true;
}

StreamFile::StreamFile(const std::string& path) : mFile(path)
{
    mFd = ::open(mFile.tempPath().c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0666);
    if (mFd < 0) throw OutputError(path + ": cannot create: " + std::strerror(errno));
}

StreamFile::~StreamFile()
{
    if (mFd >= 0) ::close(mFd); // an error on the way: AtomicFile removes the temporary
}

void StreamFile::write(const void* data, size_t size)
{
    const char* p = static_cast<const char*>(data);
    while (size > 0) {
        const ssize_t n = ::write(mFd, p, size);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            throw OutputError(mFile.target() +
                              ": write failed: " + std::strerror(n < 0 ? errno : ENOSPC));
        p += n, size -= size_t(n), mWritten += uint64_t(n);
    }
    if (mWritten - mWrittenBack >= kWriteBack) {
        // advice only: a file system that cannot do it just writes at fsync
        ::sync_file_range(mFd, off64_t(mWrittenBack), off64_t(mWritten - mWrittenBack),
                          SYNC_FILE_RANGE_WRITE);
        mWrittenBack = mWritten;
    }
}

void StreamFile::commit()
{
    const int fd = std::exchange(mFd, -1);
    if (::close(fd) != 0)
        throw OutputError(mFile.target() + ": write failed: " + std::strerror(errno));
    mFile.commit();
}

void writeFileAtomic(const std::string& path, const void* data, size_t size)
{
    StreamFile file(path);
    file.write(data, size);
    file.commit();
}

std::string OutputGroup::add(const std::string& target)
{
    mFiles.push_back(std::make_unique<AtomicFile>(target));
    return mFiles.back()->tempPath();
}

void OutputGroup::commit()
{
    for (const std::unique_ptr<AtomicFile>& f : mFiles)
        f->commit();
}

} // namespace io
} // namespace fluidsurf
