// FuzzReader.cc - libFuzzer entry point for one particle reader; FUZZ_FORMAT names its
// io::ParticleFormat (set by tools/fuzz/CMakeLists.txt). Any input must either read or throw
// fluidsurf::InputError: a crash, a sanitizer report, a hang or an out-of-memory is a bug.
#include <fluidsurf/Error.h>
#include <fluidsurf/io/ParticleIO.h>

#include <cstdint>

#ifndef FUZZ_FORMAT
#error "define FUZZ_FORMAT as an io::ParticleFormat enumerator, e.g. -DFUZZ_FORMAT=Bgeo"
#endif

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    fluidsurf::io::ReadOptions options;
    options.allowEmpty = true;
    options.dropNonFinite = true;
    try {
        fluidsurf::io::readParticlesFromMemory(
            data, size, fluidsurf::io::ParticleFormat::FUZZ_FORMAT, "fuzz", options);
    } catch (const fluidsurf::InputError&) {
    }
    return 0;
}
