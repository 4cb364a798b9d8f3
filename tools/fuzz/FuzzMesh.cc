// FuzzMesh.cc - libFuzzer entry point for one mesh reader; FUZZ_FORMAT names its io::MeshFormat
// (set by tools/fuzz/CMakeLists.txt). Any input must either read or throw
// fluidsurf::InputError: a crash, a sanitizer report, a hang or an out-of-memory is a bug.
#include <fluidsurf/Error.h>
#include <fluidsurf/io/MeshIO.h>

#include <cstdint>

#ifndef FUZZ_FORMAT
#error "define FUZZ_FORMAT as an io::MeshFormat enumerator, e.g. -DFUZZ_FORMAT=Obj"
#endif

extern "C" int LLVMFuzzerTestOneInput(const uint8_t* data, size_t size)
{
    try {
        fluidsurf::io::readMeshFromMemory(data, size, fluidsurf::io::MeshFormat::FUZZ_FORMAT,
                                          "fuzz");
    } catch (const fluidsurf::InputError&) {
    }
    return 0;
}
