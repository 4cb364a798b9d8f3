// ParticleIO.h - read and write particle frames in the formats simulators and DCC tools write.
//
// The format is chosen by the file extension and then verified against the file's magic or
// header; a mismatch, truncation or corrupt header is an InputError naming the file, the
// problem and the byte offset. No allocation is sized from a header field before that field is
// checked against the bytes actually present.
//
//   read : .vtk (legacy ASCII/BINARY), .vtu/.vtp (VTK XML), .bgeo/.bgeo.gz (Houdini v5),
//          .ply, .xyz (raw float32 triples), .csv/.txt, .npy, .vdb (PointDataGrid with "P")
//   write: .vdb (points, Blosc), .bgeo (.bgeo.gz compressed), .ply (binary), .xyz,
//          .vtk (binary POLYDATA)
//
// Positions are float32; double-precision sources are rounded once on read.
#pragma once

#include <fluidsurf/ParticleSet.h>

#include <cstdint>
#include <string>

namespace fluidsurf {
namespace io {

enum class ParticleFormat { Unknown, VtkLegacy, VtkXml, Bgeo, Ply, Xyz, Csv, Npy, VdbPoints };

/// Format implied by the file name (case-insensitive; ".bgeo.gz" is BGEO).
ParticleFormat formatFromPath(const std::string& path);
/// Format recognised from the first bytes of the data (Unknown for headerless formats).
ParticleFormat formatFromContent(const uint8_t* data, size_t size);
const char* formatName(ParticleFormat format);
bool canWriteParticles(ParticleFormat format);

struct ReadOptions
{
    /// Drop particles with NaN/Inf coordinates or past kMaxCoordinate (counted in ReadInfo)
    /// instead of failing.
    bool dropNonFinite = false;
    /// Accept a frame with zero particles instead of failing.
    bool allowEmpty = false;
};

/// What a read learned beside the particles.
struct ReadInfo
{
    ParticleFormat format = ParticleFormat::Unknown;
    std::string detail; ///< e.g. "BINARY UNSTRUCTURED_GRID", "appended raw, zlib"
    uint64_t fileBytes = 0;
    size_t droppedNonFinite = 0;
};

ParticleSet readParticles(const std::string& path, const ReadOptions& options = {},
                          ReadInfo* info = nullptr);

/// Read from memory; source names the data in error messages. VdbPoints needs a path-less
/// stream and is supported too.
ParticleSet readParticlesFromMemory(const uint8_t* data, size_t size, ParticleFormat format,
                                    const std::string& source, const ReadOptions& options = {},
                                    ReadInfo* info = nullptr);

struct WriteOptions
{
    /// Blosc compression for VDB points. (BGEO is gzip-compressed when the name ends in .gz.)
    bool compress = true;
};

/// Write atomically (temporary file + rename). OutputError when the format cannot be written or
/// an attribute does not fit it (e.g. an int64 id beyond int32 in BGEO).
void writeParticles(const ParticleSet& particles, const std::string& path,
                    const WriteOptions& options = {});

} // namespace io
} // namespace fluidsurf
