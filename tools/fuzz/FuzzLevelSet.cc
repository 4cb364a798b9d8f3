// FuzzLevelSet.cc - libFuzzer entry point for the level-set path of `fluidsurf mesh`: every grid
// of a .vdb through our walk (io/VdbCheck) and OpenVDB's reader, then the level-set choice. Any
// input must either read or throw fluidsurf::InputError: a crash, a sanitizer report, a hang or
// an out-of-memory is a bug.
#include <fluidsurf/Error.h>
#include <fluidsurf/io/LevelSetIO.h>

#include <cstdint>

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    try {
        fluidsurf::io::readLevelSetFromMemory(data, size, "fuzz");
    } catch (const fluidsurf::InputError&) {
    }
    return 0;
}
