// AtomicFile.cc - temporary file (O_EXCL, random name, flock) + fsync + rename(2).
#include <fluidsurf/Error.h>
#include <fluidsurf/io/AtomicFile.h>

#include "io/StreamFile.h"
#include "io/Temporaries.h"

#include <cerrno>
#include <cstring>
#include <ctime>
#include <dirent.h>
#include <fcntl.h>
#include <sys/file.h>
#include <sys/random.h>
#include <sys/stat.h>
#include <unistd.h>

#include <climits>
#include <cstdlib>
#include <map>
#include <mutex>
#include <set>
#include <utility>

namespace fluidsurf {
namespace io_internal {

namespace {
constexpr const char* kPrefix = ".fluidsurf-";
constexpr const char* kLegacyPrefix = ".fluidsurf-tmp-"; // PID-named, before this file's scheme
constexpr size_t kRandom = 12, kMaxExtension = 20;
constexpr double kStaleSeconds = 3600;

std::string extensionOf(const std::string& name)
{
    size_t dot = name.find_last_of('.');
    if (dot == std::string::npos || dot == 0) return std::string();
    if (name.compare(dot, std::string::npos, ".gz") == 0 && dot > 0) {
        const size_t before = name.find_last_of('.', dot - 1);
        if (before != std::string::npos && before > 0) dot = before;
    }
    const std::string ext = name.substr(dot);
    return ext.size() <= kMaxExtension ? ext : std::string();
}
} // namespace

bool isTemporaryName(const std::string& name)
{
    if (name.compare(0, std::strlen(kLegacyPrefix), kLegacyPrefix) == 0) return true;
    const size_t p = std::strlen(kPrefix);
    if (name.size() < p + kRandom || name.compare(0, p, kPrefix) != 0) return false;
    for (size_t i = p; i < p + kRandom; ++i)
        if (!((name[i] >= '0' && name[i] <= '9') || (name[i] >= 'a' && name[i] <= 'z')))
            return false;
    return name.size() == p + kRandom || name[p + kRandom] == '.';
}

std::string temporaryName(const std::string& targetName)
{
    unsigned char bytes[kRandom];
    size_t got = 0;
    while (got < kRandom) {
        const ssize_t n = ::getrandom(bytes + got, kRandom - got, 0);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0) break;
        got += size_t(n);
    }
    if (got < kRandom) { // no getrandom (old kernel, seccomp): time and address, still O_EXCL
        uint64_t x = uint64_t(std::time(nullptr)) ^ (uint64_t(::getpid()) << 32) ^
                     uint64_t(reinterpret_cast<uintptr_t>(&got)) ^ uint64_t(std::clock());
        for (size_t i = 0; i < kRandom; ++i)
            x = x * 6364136223846793005ull + 1442695040888963407ull, bytes[i] = uint8_t(x >> 56);
    }
    std::string name = kPrefix;
    for (size_t i = 0; i < kRandom; ++i)
        name += "0123456789abcdefghijklmnopqrstuvwxyz"[bytes[i] % 36];
    return name + extensionOf(targetName);
}

int removeStaleTemporaries(const std::string& folder, double maxAgeSeconds)
{
    DIR* dir = ::opendir(folder.c_str());
    if (!dir) return 0;
    int removed = 0;
    const time_t now = std::time(nullptr);
    while (const dirent* entry = ::readdir(dir)) {
        const std::string name = entry->d_name;
        if (!isTemporaryName(name)) continue;
        const std::string path = folder + (folder.back() == '/' ? "" : "/") + name;
        const int fd = ::open(path.c_str(), O_RDONLY | O_NOFOLLOW | O_NONBLOCK | O_CLOEXEC);
        if (fd < 0) continue;
        struct stat st;
        // a live run holds the lock from creation to rename; age guards the moment between
        // its open and its flock, and file systems where the lock is not seen from here
        if (::fstat(fd, &st) == 0 && S_ISREG(st.st_mode) &&
            std::difftime(now, st.st_mtime) >= maxAgeSeconds &&
            ::flock(fd, LOCK_EX | LOCK_NB) == 0 && ::unlink(path.c_str()) == 0)
            ++removed;
        ::close(fd);
    }
    ::closedir(dir);
    return removed;
}

} // namespace io_internal

namespace io {

namespace {
std::string folderOf(const std::string& path)
{
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? std::string(".") : path.substr(0, slash + 1);
}

std::string baseOf(const std::string& path)
{
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? path : path.substr(slash + 1);
}

/// Once per folder and process: a farm task writing thousands of frames reads its folder once.
void removeStaleOnce(const std::string& folder)
{
    static std::mutex mutex;
    static std::set<std::string> done;
    {
        std::lock_guard<std::mutex> lock(mutex);
        if (!done.insert(folder).second) return;
    }
    io_internal::removeStaleTemporaries(folder, io_internal::kStaleSeconds);
}

/// The temporaries of live AtomicFiles (removeLiveTemporaries).
std::mutex gLiveMutex;
std::set<std::string> gLive;

void setLive(const std::string& temp, bool live)
{
    std::lock_guard<std::mutex> lock(gLiveMutex);
    if (live)
        gLive.insert(temp);
    else
        gLive.erase(temp);
}

/// The temporaries of live OutputGroups and the names they stand for.
std::mutex gGroupMutex;
std::map<std::string, std::string> gGroupTemps;

bool groupName(const std::string& temp, std::string& name)
{
    std::lock_guard<std::mutex> lock(gGroupMutex);
    const auto it = gGroupTemps.find(temp);
    if (it == gGroupTemps.end()) return false;
    name = it->second;
    return true;
}

/// The file a symbolic link names (links to links followed, up to 40); the path itself when it
/// is no link. A relative link is relative to the link's folder.
std::string followLinks(const std::string& path)
{
    std::string p = path;
    for (int hop = 0; hop < 40; ++hop) {
        struct stat st;
        if (::lstat(p.c_str(), &st) != 0 || !S_ISLNK(st.st_mode)) return p;
        char to[PATH_MAX];
        const ssize_t n = ::readlink(p.c_str(), to, sizeof(to) - 1);
        if (n <= 0) return p;
        to[n] = 0;
        const size_t slash = p.find_last_of('/');
        p = (to[0] == '/' || slash == std::string::npos ? std::string() : p.substr(0, slash + 1)) +
            to;
    }
    return p;
}

std::string errorText(int err)
{
    return std::strerror(err);
}
} // namespace

void requireWritableFolder(const std::string& target)
{
    if (target.empty()) throw OutputError("empty output path");
    if (target.back() == '/') throw OutputError(target + ": output path names a folder");
    if (target.find('\0') != std::string::npos)
        throw OutputError("output path contains a NUL byte");
    struct stat st;
    if (::stat(target.c_str(), &st) == 0 && !S_ISREG(st.st_mode))
        throw OutputError(target + ": exists and is not a regular file (" +
                          (S_ISDIR(st.st_mode)    ? "a folder"
                           : S_ISFIFO(st.st_mode) ? "a FIFO"
                           : S_ISSOCK(st.st_mode) ? "a socket"
                                                  : "a device") +
                          "); refusing to replace it");
    const std::string folder = folderOf(followLinks(target));
    if (::access(folder.c_str(), W_OK) != 0)
        throw OutputError(target + ": cannot write into folder '" + folder +
                          "': " + errorText(errno));
}

AtomicFile::AtomicFile(const std::string& target) : mName(target), mTarget(target)
{
    if (groupName(target, mName)) { // an OutputGroup's temporary: written in place
        mInGroup = true;
        mTemp = target;
        mFd = ::open(mTemp.c_str(), O_WRONLY | O_TRUNC | O_CLOEXEC);
        if (mFd < 0) throw OutputError(mName + ": cannot create: " + errorText(errno));
        return;
    }
    requireWritableFolder(target);
    mTarget = followLinks(target);
    const std::string folder = folderOf(mTarget);
    const std::string dir = mTarget.find('/') == std::string::npos ? std::string() : folder;
    removeStaleOnce(folder);
    for (int attempt = 0; mFd < 0; ++attempt) {
        mTemp = dir + io_internal::temporaryName(baseOf(mTarget));
        mFd = ::open(mTemp.c_str(), O_WRONLY | O_CREAT | O_EXCL | O_CLOEXEC, 0666);
        if (mFd < 0 && (errno != EEXIST || attempt >= 16))
            throw OutputError(target + ": cannot create a file in '" + folder +
                              "': " + errorText(errno));
    }
    // held until the rename: another run's removeStaleTemporaries leaves a locked file alone
    // (a file system without flock just has the age guard)
    ::flock(mFd, LOCK_EX | LOCK_NB);
    setLive(mTemp, true);
}

AtomicFile::~AtomicFile()
{
    if (!mCommitted && !mInGroup) ::unlink(mTemp.c_str());
    if (!mInGroup) setLive(mTemp, false);
    if (mFd >= 0) ::close(mFd);
}

void removeLiveTemporaries()
{
    std::lock_guard<std::mutex> lock(gLiveMutex);
    for (const std::string& temp : gLive)
        ::unlink(temp.c_str());
    gLive.clear();
}

void AtomicFile::commit()
{
    // a failed fsync (EIO, ENOSPC, EDQUOT) means bytes may not have reached the disk: no
    // rename over an older good file then (file systems that cannot sync say EINVAL)
    if (::fsync(mFd) != 0 && errno != EINVAL && errno != EROFS)
        throw OutputError(mName + ": write failed at the end: " + errorText(errno));
    if (mInGroup) {
        mCommitted = true; // the group renames it
        return;
    }
    if (::rename(mTemp.c_str(), mTarget.c_str()) != 0)
        throw OutputError(mName +
                          ": cannot move the finished file into place: " + errorText(errno));
    mCommitted = true;
    setLive(mTemp, false);
    ::close(std::exchange(mFd, -1)); // the lock goes with it, after the name did
}

StreamFile::StreamFile(const std::string& path) : mFile(path), mFd(mFile.fd()) {}

StreamFile::~StreamFile() = default; // an error on the way: AtomicFile removes the temporary

void StreamFile::write(const void* data, size_t size)
{
    const char* p = static_cast<const char*>(data);
    while (size > 0) {
        const ssize_t n = ::write(mFd, p, size);
        if (n < 0 && errno == EINTR) continue;
        if (n <= 0)
            throw OutputError(mFile.name() +
                              ": write failed: " + errorText(n < 0 ? errno : ENOSPC));
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
    std::lock_guard<std::mutex> lock(gGroupMutex);
    gGroupTemps[mFiles.back()->tempPath()] = target;
    return mFiles.back()->tempPath();
}

void OutputGroup::commit()
{
    for (const std::unique_ptr<AtomicFile>& f : mFiles)
        f->commit();
}

OutputGroup::~OutputGroup()
{
    std::lock_guard<std::mutex> lock(gGroupMutex);
    for (const std::unique_ptr<AtomicFile>& f : mFiles)
        gGroupTemps.erase(f->tempPath());
}

} // namespace io
} // namespace fluidsurf
