// Formats.h - the per-format readers and writers behind ParticleIO.h. Each reader takes the
// file in memory and a source name for messages (readParticlesFromMemory); all but VTK XML and
// .vdb also read from an OpenFile, where the values lie, with no copy of the file (readParticles).
// The writers stream into a StreamFile.
#pragma once

#include <fluidsurf/ParticleSet.h>

#include <cstdint>
#include <optional>
#include <string>
#include <vector>

namespace fluidsurf {
namespace io {
class StreamFile;
class GzipStream;
} // namespace io
namespace io_internal {

using Bytes = std::vector<uint8_t>;
class OpenFile;

ParticleSet readVtkLegacy(const uint8_t* data, size_t size, const std::string& src,
                          std::string* detail);
/// A binary legacy VTK read from where its sections lie, its values by all threads with no
/// buffer of the whole file; nullopt for an ASCII file (parsed from memory). The same values and
/// messages as the file in memory.
std::optional<ParticleSet> readVtkLegacy(const OpenFile& file, const std::string& src,
                                         std::string* detail);
ParticleSet readVtkXml(const uint8_t* data, size_t size, const std::string& src,
                       std::string* detail);
ParticleSet readBgeo(const uint8_t* data, size_t size, const std::string& src, std::string* detail);
/// An uncompressed BGEO read by all threads from where its points lie, a slice each, with no
/// buffer of the whole file; nullopt for a gzip file, or one whose header or points are not all
/// there (readBgeo of the whole file then names what is wrong).
std::optional<ParticleSet> readBgeo(const OpenFile& file, const std::string& src,
                                    std::string* detail);
ParticleSet readPly(const uint8_t* data, size_t size, const std::string& src, std::string* detail);
/// A binary PLY whose vertices follow elements of fixed size only, read by all threads from
/// where they lie, a slice each, with no buffer of the whole file; nullopt otherwise, or where
/// the header or the vertices are not all there (readPly of the whole file then names what is
/// wrong).
std::optional<ParticleSet> readPly(const OpenFile& file, const std::string& src,
                                   std::string* detail);
/// A raw .xyz whose size is not a multiple of 12 (and whose first bytes are not text): InputError.
void checkXyzSize(const uint8_t* head, size_t headBytes, uint64_t fileBytes,
                  const std::string& src);
ParticleSet readXyz(const uint8_t* data, size_t size, const std::string& src, std::string* detail);
/// Whether a .xyz whose first bytes are these is text (read as CSV), not raw float32.
bool isTextXyz(const uint8_t* head, size_t headBytes);
/// A raw .xyz (checkXyzSize passed) straight from the file into the positions.
ParticleSet readXyz(const OpenFile& file, std::string* detail);
ParticleSet readCsv(const uint8_t* data, size_t size, const std::string& src, std::string* detail);
/// The text read a piece at a time by the tasks that parse it, with no copy of the whole file: the
/// same values and messages.
ParticleSet readCsv(const OpenFile& file, const std::string& src, std::string* detail);
ParticleSet readNpy(const uint8_t* data, size_t size, const std::string& src, std::string* detail);
/// The array read by all threads from where it lies in the file: the same values and messages.
ParticleSet readNpy(const OpenFile& file, const std::string& src, std::string* detail);
ParticleSet readVdbPoints(const uint8_t* data, size_t size, const std::string& src,
                          std::string* detail);

/// Streamed into out, encoded in parallel blocks (StreamFile.h's writeItems): no whole file in
/// memory. OutputError for what the format cannot hold, before anything is written.
void writeBgeo(const ParticleSet& particles, io::StreamFile& out);
/// `.bgeo.gz`: the same bytes through out, compressed on all threads (GzipStream.h).
void writeBgeo(const ParticleSet& particles, io::GzipStream& out);
void writeVtkLegacy(const ParticleSet& particles, io::StreamFile& out);
void writePly(const ParticleSet& particles, io::StreamFile& out);
void writeXyz(const ParticleSet& particles, io::StreamFile& out);
void writeVdbPoints(const ParticleSet& particles, const std::string& path, bool compress);

/// Parse a decimal number of the whole token (no trailing garbage); false if it is not one.
bool parseFloat(const char* begin, const char* end, double& value);
bool parseInt(const char* begin, const char* end, int64_t& value);

} // namespace io_internal
} // namespace fluidsurf
