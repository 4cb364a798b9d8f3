// TestData.cc
#include "TestData.h"

#include <fluidsurf/Error.h>

#include <zlib.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <sys/stat.h>
#include <unistd.h>

namespace fluidsurf {
namespace test {

std::string sharedData()
{
    for (const char* candidate : {FLUIDSURF_SHARED_DATA, "../shared/data"}) {
        struct stat st;
        if (::stat((std::string(candidate) + "/real").c_str(), &st) == 0 && S_ISDIR(st.st_mode))
            return candidate;
    }
    return "";
}

TempDir::TempDir()
{
    char templ[] = "/tmp/fluidsurf_test_XXXXXX";
    if (!::mkdtemp(templ)) throw std::runtime_error("mkdtemp failed");
    mPath = templ;
}

TempDir::~TempDir()
{
    const std::string cmd = "rm -rf '" + mPath + "'";
    if (std::system(cmd.c_str()) != 0) std::fprintf(stderr, "cannot remove %s\n", mPath.c_str());
}

void writeFile(const std::string& path, const std::string& bytes)
{
    std::ofstream f(path, std::ios::binary);
    f.write(bytes.data(), std::streamsize(bytes.size()));
}

std::string readFileBytes(const std::string& path)
{
    std::ifstream f(path, std::ios::binary);
    std::stringstream ss;
    ss << f.rdbuf();
    return ss.str();
}

bool fileExists(const std::string& path)
{
    struct stat st;
    return ::stat(path.c_str(), &st) == 0;
}

std::string gzipBytes(const std::string& data)
{
    z_stream zs{};
    deflateInit2(&zs, 6, Z_DEFLATED, 15 + 16, 8, Z_DEFAULT_STRATEGY);
    std::string out(deflateBound(&zs, uLong(data.size())) + 64, '\0');
    zs.next_in = reinterpret_cast<Bytef*>(const_cast<char*>(data.data()));
    zs.avail_in = uInt(data.size());
    zs.next_out = reinterpret_cast<Bytef*>(&out[0]);
    zs.avail_out = uInt(out.size());
    deflate(&zs, Z_FINISH);
    out.resize(zs.total_out);
    deflateEnd(&zs);
    return out;
}

std::string zlibBytes(const std::string& data)
{
    uLongf n = compressBound(uLong(data.size()));
    std::string out(n, '\0');
    compress(reinterpret_cast<Bytef*>(&out[0]), &n, reinterpret_cast<const Bytef*>(data.data()),
             uLong(data.size()));
    out.resize(n);
    return out;
}

std::string base64(const std::string& d)
{
    static const char* k = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    std::string out;
    for (size_t i = 0; i < d.size(); i += 3) {
        uint32_t v = uint32_t(uint8_t(d[i])) << 16;
        if (i + 1 < d.size()) v |= uint32_t(uint8_t(d[i + 1])) << 8;
        if (i + 2 < d.size()) v |= uint32_t(uint8_t(d[i + 2]));
        out += k[(v >> 18) & 63];
        out += k[(v >> 12) & 63];
        out += i + 1 < d.size() ? k[(v >> 6) & 63] : '=';
        out += i + 2 < d.size() ? k[v & 63] : '=';
    }
    return out;
}

ParticleSet readBytes(const std::string& bytes, io::ParticleFormat format, const io::ReadOptions& o)
{
    return io::readParticlesFromMemory(reinterpret_cast<const uint8_t*>(bytes.data()), bytes.size(),
                                       format, "test-input", o);
}

std::vector<std::pair<std::string, ParticleSet>>
readFromMemoryAndFile(const std::string& bytes, io::ParticleFormat format, const std::string& path)
{
    std::vector<std::pair<std::string, ParticleSet>> sets;
    sets.emplace_back("from memory", readBytes(bytes, format));
    writeFile(path, bytes);
    sets.emplace_back("from the file", io::readParticles(path));
    return sets;
}

std::string readError(const std::string& bytes, io::ParticleFormat format)
{
    try {
        readBytes(bytes, format);
    } catch (const InputError& e) {
        return e.what();
    }
    return "";
}

} // namespace test
} // namespace fluidsurf
