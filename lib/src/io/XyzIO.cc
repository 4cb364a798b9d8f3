// XyzIO.cc - raw .xyz: little-endian float32 x y z triples, no header (DualSPHysics exports,
// splashsurf). A text file named .xyz (the other common meaning of the extension) is
// recognised and handed to the CSV reader instead of being misread as binary.
#include "io/ByteReader.h"
#include "io/FileBuffer.h"
#include "io/Formats.h"
#include "io/StreamFile.h"
#include "io/TextParse.h"

#include "util/Memory.h"

#include <fluidsurf/Error.h>

namespace fluidsurf {
namespace io_internal {

bool isTextXyz(const uint8_t* d, size_t size)
{
    const size_t n = std::min<size_t>(size, 4096);
    if (n == 0) return false;
    for (size_t i = 0; i < n; ++i) {
        const uint8_t c = d[i];
        if (!(isSpace(c) || std::isdigit(c) || c == '.' || c == '-' || c == '+' || c == 'e' ||
              c == 'E' || c == ',' || c == ';' || c == '#'))
            return false;
    }
    return true;
}

void checkXyzSize(const uint8_t* head, size_t headBytes, uint64_t fileBytes, const std::string& src)
{
    if (isTextXyz(head, headBytes) || fileBytes % 12 == 0) return;
    throw InputError(src + ": raw .xyz size " + std::to_string(fileBytes) +
                     " is not a multiple of 12 bytes (3 float32 per particle): truncated or not "
                     "raw float32 xyz (at byte " +
                     std::to_string(fileBytes - fileBytes % 12) + ")");
}

ParticleSet readXyz(const uint8_t* data, size_t size, const std::string& src, std::string* detail)
{
    if (isTextXyz(data, size)) {
        ParticleSet set = readCsv(data, size, src, detail);
        if (detail) *detail = "ASCII text (" + *detail + ")";
        return set;
    }
    ByteReader in(data, size, src);
    if (size % 12 != 0)
        in.failAt(size - size % 12, "raw .xyz size " + std::to_string(size) +
                                        " is not a multiple of 12 bytes (3 float32 per particle): "
                                        "truncated or not raw float32 xyz");
    ParticleSet set;
    set.positions.resize(size / 12);
    if (size) std::memcpy(set.positions.data(), data, size); // little-endian host
    if (detail) *detail = "raw float32 little-endian";
    return set;
}

ParticleSet readXyz(const OpenFile& file, std::string* detail)
{
    ParticleSet set;
    util::resizeInParallel(set.positions, size_t(file.size() / 12));
    file.readAt(0, set.positions.data(), set.positions.size() * 12); // little-endian host
    if (detail) *detail = "raw float32 little-endian";
    return set;
}

void writeXyz(const ParticleSet& ps, io::StreamFile& out)
{
    // the positions as they lie (little-endian host), a piece at a time so that the disk starts
    // on the first pieces while the rest are written (no copy of the file in memory)
    const char* p = reinterpret_cast<const char*>(ps.positions.data());
    const size_t size = ps.size() * 12;
    for (size_t at = 0; at < size; at += io::StreamFile::kWriteBack)
        out.write(p + at, std::min<size_t>(io::StreamFile::kWriteBack, size - at));
}

} // namespace io_internal
} // namespace fluidsurf
