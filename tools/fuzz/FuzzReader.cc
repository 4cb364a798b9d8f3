// FuzzReader.cc - libFuzzer entry point for one particle reader (chosen by FUZZ_FORMAT_<ext>).
// Any input must either read or throw fluidsurf::InputError: a crash, a sanitizer report, a
// hang or an out-of-memory is a bug.
#include <fluidsurf/Error.h>
#include <fluidsurf/io/ParticleIO.h>

#include <cstdint>

namespace {
using fluidsurf::io::ParticleFormat;
#if defined(FUZZ_FORMAT_bgeo)
constexpr ParticleFormat kFormat = ParticleFormat::Bgeo;
#elif defined(FUZZ_FORMAT_vtk)
constexpr ParticleFormat kFormat = ParticleFormat::VtkLegacy;
#elif defined(FUZZ_FORMAT_vtu)
constexpr ParticleFormat kFormat = ParticleFormat::VtkXml;
#elif defined(FUZZ_FORMAT_ply)
constexpr ParticleFormat kFormat = ParticleFormat::Ply;
#elif defined(FUZZ_FORMAT_npy)
constexpr ParticleFormat kFormat = ParticleFormat::Npy;
#elif defined(FUZZ_FORMAT_xyz)
constexpr ParticleFormat kFormat = ParticleFormat::Xyz;
#elif defined(FUZZ_FORMAT_vdb)
constexpr ParticleFormat kFormat = ParticleFormat::VdbPoints;
#else
#error "define FUZZ_FORMAT_<ext>"
#endif
} // namespace

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    fluidsurf::io::ReadOptions options;
    options.allowEmpty = true;
    options.dropNonFinite = true;
    try {
        fluidsurf::io::readParticlesFromMemory(data, size, kFormat, "fuzz", options);
    } catch (const fluidsurf::InputError&) {
    }
    return 0;
}
