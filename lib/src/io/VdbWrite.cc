// VdbWrite.cc - .vdb files through a checked stream (see VdbWrite.h).
#include "io/VdbWrite.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/io/AtomicFile.h>

#include <openvdb/io/Archive.h>

#include <cerrno>
#include <cstdio>
#include <cstring>
#include <memory>
#include <ostream>
#include <streambuf>
#include <vector>

#include <fcntl.h>
#include <unistd.h>

namespace fluidsurf {
namespace io_internal {

namespace {

/// An output stream buffer over a file descriptor that remembers the first failed write (its
/// errno) and fails every write after it. Seekable: OpenVDB seeks back to fill in the grid
/// offsets of a seekable archive.
class CheckedFdBuf : public std::streambuf
{
public:
    explicit CheckedFdBuf(int fd) : mFd(fd), mBuffer(size_t(1) << 20)
    {
        setp(mBuffer.data(), mBuffer.data() + mBuffer.size());
    }
    int error() const { return mError; }
    /// Whatever is buffered to the file; false (with error()) when it could not be written.
    bool flush() { return drain() && mError == 0; }

protected:
    int_type overflow(int_type c) override
    {
        if (!drain()) return traits_type::eof();
        if (!traits_type::eq_int_type(c, traits_type::eof())) {
            *pptr() = traits_type::to_char_type(c);
            pbump(1);
        }
        return traits_type::not_eof(c);
    }
    std::streamsize xsputn(const char* s, std::streamsize n) override
    {
        if (n <= epptr() - pptr()) {
            std::memcpy(pptr(), s, size_t(n));
            pbump(int(n));
            return n;
        }
        if (!drain() || !writeAll(s, size_t(n))) return 0;
        return n;
    }
    int sync() override { return drain() ? 0 : -1; }
    pos_type seekoff(off_type off, std::ios_base::seekdir dir, std::ios_base::openmode) override
    {
        if (!drain()) return pos_type(off_type(-1));
        const int whence = dir == std::ios_base::beg   ? SEEK_SET
                           : dir == std::ios_base::cur ? SEEK_CUR
                                                       : SEEK_END;
        const off_t at = ::lseek(mFd, off_t(off), whence);
        return at < 0 ? pos_type(off_type(-1)) : pos_type(off_type(at));
    }
    pos_type seekpos(pos_type pos, std::ios_base::openmode which) override
    {
        return seekoff(off_type(pos), std::ios_base::beg, which);
    }

private:
    bool drain()
    {
        const size_t n = size_t(pptr() - pbase());
        setp(mBuffer.data(), mBuffer.data() + mBuffer.size());
        return n == 0 ? mError == 0 : writeAll(mBuffer.data(), n);
    }
    bool writeAll(const char* p, size_t n)
    {
        if (mError) return false;
        while (n > 0) {
            const ssize_t w = ::write(mFd, p, n);
            if (w < 0 && errno == EINTR) continue;
            if (w <= 0) {
                mError = w < 0 ? errno : ENOSPC;
                return false;
            }
            p += w, n -= size_t(w);
        }
        return true;
    }

    int mFd;
    std::vector<char> mBuffer;
    int mError = 0;
};

/// OpenVDB's archive writer, reached for a stream of ours (io::File would open its own).
class StreamArchive : public openvdb::io::Archive
{
public:
    void writeTo(std::ostream& os, const openvdb::GridCPtrVec& grids) const
    {
        Archive::write(os, grids, /*seekable=*/true);
    }
};

// OpenVDB's file header: magic (8 bytes), file version, library major and minor (4 each), the
// grid-offsets flag (1), then a random UUID as 36 characters. The UUID only identifies a file
// for caches, so a hash of the content serves better: equal grids give equal bytes.
constexpr size_t kUuidOffset = 8 + 4 + 4 + 4 + 1, kUuidLength = 36;

/// The file's bytes after the UUID, hashed as they are read back a chunk at a time. Read into
/// one vector through a stream iterator, the file took as long as OpenVDB took to write it (0.37
/// s of the 1.7M-particle frame's 0.85 s `write`) and held a second copy of it at the peak.
void makeUuidDeterministic(const std::string& temp, const std::string& name)
{
    const int fd = ::open(temp.c_str(), O_RDWR | O_CLOEXEC);
    if (fd < 0) throw OutputError(name + ": cannot read back the written file");
    struct Closer
    {
        int fd;
        ~Closer() { ::close(fd); }
    } closer{fd};
    // (pread returns short counts only at the end of the file or when interrupted)
    auto readAt = [&](uint8_t* to, size_t n, size_t at) {
        size_t done = 0;
        while (done < n) {
            const ssize_t got = ::pread(fd, to + done, n - done, off_t(at + done));
            if (got < 0 && errno == EINTR) continue;
            if (got < 0) throw OutputError(name + ": cannot read back the written file");
            if (got == 0) break;
            done += size_t(got);
        }
        return done;
    };
    uint8_t head[kUuidOffset + kUuidLength];
    if (readAt(head, sizeof head, 0) < sizeof head || head[kUuidOffset + 8] != '-' ||
        head[kUuidOffset + 13] != '-')
        throw OutputError(name + ": OpenVDB wrote an unexpected header (its version?)");
    constexpr size_t kChunk = size_t(4) << 20;
    const std::unique_ptr<uint8_t[]> chunk(new uint8_t[kChunk]);
    uint64_t h0 = 0xcbf29ce484222325ull, h1 = 0x84222325cbf29ce4ull; // two FNV-1a streams
    for (size_t at = sizeof head;;) {
        const size_t got = readAt(chunk.get(), kChunk, at);
        for (size_t i = 0; i < got; ++i) {
            h0 = (h0 ^ chunk[i]) * 0x100000001b3ull;
            h1 = (h1 ^ chunk[i] ^ 0x5a) * 0x100000001b3ull;
        }
        if (got < kChunk) break;
        at += got;
    }
    char uuid[40];
    std::snprintf(uuid, sizeof(uuid), "%08x-%04x-%04x-%04x-%012llx", unsigned(h0 >> 32),
                  unsigned(h0 >> 16) & 0xffff, (unsigned(h0) & 0x0fff) | 0x4000,
                  (unsigned(h1 >> 48) & 0x3fff) | 0x8000,
                  (unsigned long long)(h1 & 0xffffffffffffull));
    if (::pwrite(fd, uuid, kUuidLength, off_t(kUuidOffset)) != ssize_t(kUuidLength))
        throw OutputError(name + ": cannot write the file header: " + std::strerror(errno));
}

} // namespace

void writeVdbFile(const openvdb::GridCPtrVec& grids, const std::string& path, uint32_t compression,
                  bool uuidFromContent)
{
    openvdb::initialize();
    io::AtomicFile out(path);
    {
        CheckedFdBuf buffer(out.fd());
        std::ostream os(&buffer);
        try {
            StreamArchive archive;
            archive.setCompression(compression);
            archive.writeTo(os, grids);
        } catch (const std::exception& e) {
            if (!buffer.error()) throw OutputError(out.name() + ": cannot write VDB: " + e.what());
        }
        if (!buffer.flush() || !os.good())
            throw OutputError(out.name() + ": write failed: " +
                              std::strerror(buffer.error() ? buffer.error() : EIO));
    }
    if (uuidFromContent) makeUuidDeterministic(out.tempPath(), out.name());
    out.commit();
}

} // namespace io_internal
} // namespace fluidsurf
