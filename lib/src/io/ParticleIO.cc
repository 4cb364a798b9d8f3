// ParticleIO.cc - format selection (extension, then content check), the common checks every
// frame passes (non-finite positions, empty frames, attribute sizes) and atomic writing.
#include <fluidsurf/io/ParticleIO.h>

#include "io/FileBuffer.h"
#include "io/Formats.h"
#include "io/GzipStream.h"
#include "io/StreamFile.h"
#include "io/TextParse.h"

#include <fluidsurf/Error.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <utility>

namespace fluidsurf {
namespace io {

using namespace io_internal;

namespace {
bool endsWith(const std::string& s, const std::string& suffix)
{
    return s.size() >= suffix.size() &&
           s.compare(s.size() - suffix.size(), suffix.size(), suffix) == 0;
}
} // namespace

ParticleFormat formatFromPath(const std::string& path)
{
    const std::string p = lower(path);
    if (endsWith(p, ".vtk")) return ParticleFormat::VtkLegacy;
    if (endsWith(p, ".vtu") || endsWith(p, ".vtp")) return ParticleFormat::VtkXml;
    if (endsWith(p, ".bgeo") || endsWith(p, ".bgeo.gz")) return ParticleFormat::Bgeo;
    if (endsWith(p, ".ply")) return ParticleFormat::Ply;
    if (endsWith(p, ".xyz")) return ParticleFormat::Xyz;
    if (endsWith(p, ".csv") || endsWith(p, ".txt")) return ParticleFormat::Csv;
    if (endsWith(p, ".npy")) return ParticleFormat::Npy;
    if (endsWith(p, ".vdb")) return ParticleFormat::VdbPoints;
    return ParticleFormat::Unknown;
}

ParticleFormat formatFromContent(const uint8_t* d, size_t n)
{
    auto starts = [&](const char* magic) {
        return n >= std::strlen(magic) && std::memcmp(d, magic, std::strlen(magic)) == 0;
    };
    if (starts("# vtk DataFile")) return ParticleFormat::VtkLegacy;
    if (starts("BgeoV") || isGzip(d, n))
        return ParticleFormat::Bgeo; // gzip: BGEO is our only gzip format
    if (starts("ply\n") || starts("ply\r")) return ParticleFormat::Ply;
    if (starts("\x93NUMPY")) return ParticleFormat::Npy;
    if (n >= 4 && d[0] == 0x20 && d[1] == 0x42 && d[2] == 0x44 && d[3] == 0x56)
        return ParticleFormat::VdbPoints;
    if (starts("<?xml") || starts("<VTKFile")) return ParticleFormat::VtkXml;
    return ParticleFormat::Unknown;
}

const char* formatName(ParticleFormat f)
{
    switch (f) {
    case ParticleFormat::VtkLegacy:
        return "legacy VTK";
    case ParticleFormat::VtkXml:
        return "VTK XML";
    case ParticleFormat::Bgeo:
        return "Houdini BGEO";
    case ParticleFormat::Ply:
        return "PLY";
    case ParticleFormat::Xyz:
        return "raw XYZ";
    case ParticleFormat::Csv:
        return "CSV/text";
    case ParticleFormat::Npy:
        return "NumPy .npy";
    case ParticleFormat::VdbPoints:
        return "OpenVDB points";
    case ParticleFormat::Unknown:
        break;
    }
    return "unknown";
}

bool canWriteParticles(ParticleFormat f)
{
    return f == ParticleFormat::VdbPoints || f == ParticleFormat::Bgeo ||
           f == ParticleFormat::Ply || f == ParticleFormat::Xyz || f == ParticleFormat::VtkLegacy;
}

namespace {
/// InputError if the content's magic says another format than the name.
void checkContent(const uint8_t* data, size_t size, ParticleFormat format,
                  const std::string& source)
{
    const ParticleFormat content = formatFromContent(data, size);
    if (content != ParticleFormat::Unknown && content != format &&
        !(format == ParticleFormat::VtkXml && content == ParticleFormat::VtkXml))
        throw InputError(source + ": the name says " + formatName(format) + " but the content is " +
                         formatName(content) + " (at byte 0)");
}

/// The checks every frame passes, whatever its format: attribute sizes, non-finite positions
/// (dropped or refused), an empty frame.
ParticleSet checked(ParticleSet set, ParticleFormat format, const std::string& source,
                    const std::string& detail, size_t fileBytes, const ReadOptions& options,
                    ReadInfo* info)
{
    try {
        set.validate();
    } catch (const ValueError& e) {
        throw InputError(source + ": " + e.what());
    }
    using Bad = std::pair<size_t, size_t>; // how many, the first
    const Bad none{0, SIZE_MAX};
    const Bad found = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, set.size()), none,
        [&](const tbb::blocked_range<size_t>& r, Bad b) {
            for (size_t i = r.begin(); i != r.end(); ++i)
                if (!set.positions[i].isFinite()) b.second = std::min(b.second, i), ++b.first;
            return b;
        },
        [](const Bad& a, const Bad& b) {
            return Bad(a.first + b.first, std::min(a.second, b.second));
        });
    const size_t bad = found.first;
    size_t dropped = 0;
    if (bad && !options.dropNonFinite)
        throw InputError(source + ": " + std::to_string(bad) +
                         " particle(s) have NaN/Inf coordinates (first: particle " +
                         std::to_string(found.second) + "); use --drop-nonfinite to drop them");
    // (positions past kMaxCoordinate are read as they are, for convert and info; the pipeline
    // refuses them, and asked to drop, the reader drops them with the non-finite ones)
    if (options.dropNonFinite) dropped = set.dropNonFinite();
    if (set.empty() && !options.allowEmpty)
        throw InputError(source + ": contains no particles" +
                         std::string(dropped ? " after dropping non-finite ones" : ""));
    if (info) {
        info->format = format;
        info->detail = detail;
        info->fileBytes = fileBytes;
        info->droppedNonFinite = dropped;
    }
    return set;
}
} // namespace

ParticleSet readParticlesFromMemory(const uint8_t* data, size_t size, ParticleFormat format,
                                    const std::string& source, const ReadOptions& options,
                                    ReadInfo* info)
{
    // An empty file is an error in every format (a headerless .xyz too: nothing says it is
    // particles at all); a file whose header says 0 particles is an empty frame.
    if (size == 0) throw InputError(source + ": file is empty");
    checkContent(data, size, format, source);
    std::string detail;
    ParticleSet set;
    switch (format) {
    case ParticleFormat::VtkLegacy:
        set = readVtkLegacy(data, size, source, &detail);
        break;
    case ParticleFormat::VtkXml:
        set = readVtkXml(data, size, source, &detail);
        break;
    case ParticleFormat::Bgeo:
        set = readBgeo(data, size, source, &detail);
        break;
    case ParticleFormat::Ply:
        set = readPly(data, size, source, &detail);
        break;
    case ParticleFormat::Xyz:
        set = readXyz(data, size, source, &detail);
        break;
    case ParticleFormat::Csv:
        set = readCsv(data, size, source, &detail);
        break;
    case ParticleFormat::Npy:
        set = readNpy(data, size, source, &detail);
        break;
    case ParticleFormat::VdbPoints:
        set = readVdbPoints(data, size, source, &detail);
        break;
    case ParticleFormat::Unknown:
        throw InputError(source + ": unknown particle file type (extensions: .vtk .vtu .vtp .bgeo "
                                  ".bgeo.gz .ply .xyz .csv .txt .npy .vdb)");
    }
    return checked(std::move(set), format, source, detail, size, options, info);
}

ParticleSet readParticles(const std::string& path, const ReadOptions& options, ReadInfo* info)
{
    const ParticleFormat format = formatFromPath(path);
    if (format == ParticleFormat::Unknown)
        throw InputError(path + ": unknown particle file type (extensions: .vtk .vtu .vtp .bgeo "
                                ".bgeo.gz .ply .xyz .csv .txt .npy .vdb)");
    if (format != ParticleFormat::VtkXml && format != ParticleFormat::VdbPoints) {
        // read from the file where the values lie, by all threads, with no buffer of the whole
        // file (a 13.1M-particle frame is 157 MB as raw .xyz, 423 MB as text)
        const OpenFile file(path);
        const std::vector<uint8_t> head = file.readHead(4096);
        const size_t n = head.size();
        std::string detail;
        std::optional<ParticleSet> set;
        if (n > 0) {
            checkContent(head.data(), n, format, path);
            const bool text = format == ParticleFormat::Xyz && isTextXyz(head.data(), n);
            if (format == ParticleFormat::Xyz && !text) {
                checkXyzSize(head.data(), n, file.size(), path);
                set = readXyz(file, &detail);
            } else if (text || format == ParticleFormat::Csv) {
                set = readCsv(file, path, &detail);
                if (text) detail = "ASCII text (" + detail + ")";
            } else if (format == ParticleFormat::Bgeo) {
                set = readBgeo(file, path, &detail); // nullopt: gzip, or what the file lacks
            } else if (format == ParticleFormat::Ply) {
                set = readPly(file, path, &detail); // nullopt: ASCII, or what the file lacks
            } else if (format == ParticleFormat::Npy) {
                set = readNpy(file, path, &detail);
            } else {
                set = readVtkLegacy(file, path, &detail); // nullopt: ASCII
            }
        }
        if (set)
            return checked(std::move(*set), format, path, detail, size_t(file.size()), options,
                           info);
    }
    const std::vector<uint8_t> data = readFile(path);
    return readParticlesFromMemory(data.data(), data.size(), format, path, options, info);
}

void writeParticles(const ParticleSet& particles, const std::string& path,
                    const WriteOptions& options)
{
    const ParticleFormat format = formatFromPath(path);
    if (!canWriteParticles(format))
        throw OutputError(path + ": cannot write particles as " + formatName(format) +
                          " (writable: .vdb .bgeo .bgeo.gz .ply .xyz .vtk)");
    try {
        particles.validate();
    } catch (const ValueError& e) {
        throw OutputError(path + ": " + e.what());
    }
    try {
        if (format == ParticleFormat::VdbPoints) {
            writeVdbPoints(particles, path, options.compress);
        } else if (format == ParticleFormat::Bgeo && endsWith(lower(path), ".gz")) {
            io::StreamFile out(path);
            io::GzipStream zipped(out);
            writeBgeo(particles, zipped);
            zipped.finish();
            out.commit();
        } else {
            // streamed: the temporary goes if anything fails on the way
            io::StreamFile out(path);
            if (format == ParticleFormat::Bgeo)
                writeBgeo(particles, out);
            else if (format == ParticleFormat::Ply)
                writePly(particles, out);
            else if (format == ParticleFormat::Xyz)
                writeXyz(particles, out);
            else
                writeVtkLegacy(particles, out);
            out.commit();
        }
    } catch (const OutputError& e) {
        const std::string msg = e.what();
        throw OutputError(msg.rfind(path, 0) == 0 ? msg : path + ": " + msg);
    }
}

} // namespace io
} // namespace fluidsurf
