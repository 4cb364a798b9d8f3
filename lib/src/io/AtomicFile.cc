// AtomicFile.cc - temporary file + fsync + rename(2).
#include <fluidsurf/Error.h>
#include <fluidsurf/io/AtomicFile.h>

#include <atomic>
#include <cerrno>
#include <cstdio>
#include <cstring>
#include <fcntl.h>
#include <unistd.h>

namespace fluidsurf {
namespace io {

namespace {
std::string folderOf(const std::string& path)
{
    const size_t slash = path.find_last_of('/');
    return slash == std::string::npos ? std::string(".") : path.substr(0, slash + 1);
}
} // namespace

AtomicFile::AtomicFile(const std::string& target) : mTarget(target)
{
    if (target.empty()) throw OutputError("empty output path");
    if (target.back() == '/') throw OutputError(target + ": output path names a folder");
    if (::access(folderOf(target).c_str(), W_OK) != 0)
        throw OutputError(target + ": cannot write into folder '" + folderOf(target) +
                          "': " + std::strerror(errno));
    static std::atomic<unsigned> counter{0};
    // Hidden name in the same folder: rename() stays atomic (same file system).
    const size_t slash = target.find_last_of('/');
    const std::string base = slash == std::string::npos ? target : target.substr(slash + 1);
    const std::string dir =
        slash == std::string::npos ? std::string() : target.substr(0, slash + 1);
    mTemp =
        dir + "." + base + ".tmp" + std::to_string(::getpid()) + "_" + std::to_string(counter++);
}

AtomicFile::~AtomicFile()
{
    if (!mCommitted) ::unlink(mTemp.c_str());
}

void AtomicFile::commit()
{
    int fd = ::open(mTemp.c_str(), O_RDONLY);
    if (fd >= 0) {
        ::fsync(fd);
        ::close(fd);
    }
    if (::rename(mTemp.c_str(), mTarget.c_str()) != 0)
        throw OutputError(mTarget +
                          ": cannot move the finished file into place: " + std::strerror(errno));
    mCommitted = true;
}

void writeFileAtomic(const std::string& path, const void* data, size_t size)
{
    AtomicFile file(path);
    FILE* f = std::fopen(file.tempPath().c_str(), "wb");
    if (!f) throw OutputError(path + ": cannot create: " + std::strerror(errno));
    const size_t written = size ? std::fwrite(data, 1, size, f) : 0;
    const bool ok = written == size && std::fflush(f) == 0;
    const int err = errno;
    if (std::fclose(f) != 0 || !ok)
        throw OutputError(path + ": write failed: " + std::strerror(ok ? errno : err));
    file.commit();
}

} // namespace io
} // namespace fluidsurf
