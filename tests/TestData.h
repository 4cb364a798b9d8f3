// TestData.h - helpers shared by the tests: the shared real frames (skipped when absent), temp
// folders, and a byte builder for writing test files by hand, independent of the library's own
// encoders.
#pragma once

#include <fluidsurf/Error.h>
#include <fluidsurf/io/ParticleIO.h>

#include <gtest/gtest.h>

#include <cstring>
#include <string>
#include <utility>
#include <vector>

namespace fluidsurf {
namespace test {

/// ../shared/data, or "" when it is not there (a user's fresh clone).
std::string sharedData();

#define FLUIDSURF_REQUIRE_SHARED_DATA()                                                            \
    do {                                                                                           \
        if (::fluidsurf::test::sharedData().empty())                                               \
            GTEST_SKIP() << "../shared/data is absent: real-frame test skipped";                   \
    } while (0)

/// The small frames of ../shared/data/real with their particle radius (its README).
struct RealFrame
{
    const char* name;
    double radius;
    bool fluid = true; ///< written by a fluid simulator (not scattered points)
};

inline const RealFrame kRealFrames[] = {
    {"double_dam_break_frame_26_4732_particles.vtk", 0.025},
    {"dam_break_frame_9_6859_particles.bgeo", 0.025},
    {"dam_break_frame_23_24389_particles.bgeo", 0.025},
    {"hilbert_46843_particles.bgeo", 0.025},
    {"bunny_frame_14_7705_particles.vtk", 0.025},
    {"cube_2366_particles.vtk", 0.025},
    {"free_particles_1000_particles.vtk", 0.5, false},
    {"ParticleData_Random_1000.vtk", 0.025, false},
    {"fluid_250_particles.vtu", 0.025},
    {"fluid_encoded_250_particles.vtu", 0.025},
    {"splishsplash_sphere_12394_particles.bgeo", 0.025},
    {"splishsplash_particle_grid_400_particles.bgeo", 0.025},
};

/// The large frames of ../shared/data/large (DualSPHysics, the thesis' scale: benchmarks, and
/// the few tests that must hold there too) with their particle radius (its README).
inline const RealFrame kLargeFrames[] = {
    {"dam_obstacle_t0.20_1704086_particles.xyz", 0.0018},
    {"dam_obstacle_t0.50_1694136_particles.xyz", 0.0018},
    {"dam_obstacle_t0.50_398850_particles.vtk", 0.0029},
};

/// A fresh folder under /tmp, removed with its content on destruction.
class TempDir
{
public:
    TempDir();
    ~TempDir();
    std::string path(const std::string& name) const { return mPath + "/" + name; }
    const std::string& path() const { return mPath; }

private:
    std::string mPath;
};

void writeFile(const std::string& path, const std::string& bytes);
std::string readFileBytes(const std::string& path);
bool fileExists(const std::string& path);

/// Append-only byte builder with explicit endianness.
struct ByteBuilder
{
    std::string s;
    template <typename T> ByteBuilder& be(T v)
    {
        char b[sizeof(T)];
        std::memcpy(b, &v, sizeof(T));
        for (size_t i = 0; i < sizeof(T); ++i)
            s += b[sizeof(T) - 1 - i];
        return *this;
    }
    template <typename T> ByteBuilder& le(T v)
    {
        char b[sizeof(T)];
        std::memcpy(b, &v, sizeof(T));
        s.append(b, sizeof(T));
        return *this;
    }
    ByteBuilder& text(const std::string& t)
    {
        s += t;
        return *this;
    }
};

std::string gzipBytes(const std::string& data);
std::string zlibBytes(const std::string& data);
std::string base64(const std::string& data);

/// Read bytes as the given format through the public API.
ParticleSet readBytes(const std::string& bytes, io::ParticleFormat format,
                      const io::ReadOptions& o = {});

/// Bytes read both ways a reader is reached: from memory (readBytes), then written to path and
/// read from the file (io::readParticles, which reads where the values lie). Each set comes with
/// the way's name, for SCOPED_TRACE.
std::vector<std::pair<std::string, ParticleSet>>
readFromMemoryAndFile(const std::string& bytes, io::ParticleFormat format, const std::string& path);

/// The InputError message of reading bytes, or "" if it read fine.
std::string readError(const std::string& bytes, io::ParticleFormat format);

} // namespace test
} // namespace fluidsurf
