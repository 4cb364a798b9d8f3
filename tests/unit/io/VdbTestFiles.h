// VdbTestFiles.h - .vdb bytes written by OpenVDB itself, for the tests of the walk every .vdb
// goes through before OpenVDB reads it (VdbCheckTest, VdbPointBuffersTest), and a reader of
// corrupted copies.
#pragma once

#include "io/VdbGrids.h"

#include <fluidsurf/Error.h>

#include <openvdb/io/File.h>
#include <openvdb/io/Stream.h>

#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

namespace fluidsurf {
namespace test {

using Bytes = std::vector<uint8_t>;

inline Bytes toBytes(const std::string& s)
{
    return Bytes(s.begin(), s.end());
}

/// grids written through io::Stream (no grid offsets) or io::File (offsets, as every .vdb on
/// disk), with the given compression.
inline Bytes writeVdb(const openvdb::GridPtrVec& grids, uint32_t compression, bool file)
{
    if (!file) {
        std::ostringstream os(std::ios::binary);
        openvdb::io::Stream s(os);
        s.setCompression(compression);
        s.write(grids);
        return toBytes(os.str());
    }
    // one name per process: ctest runs the tests of this file in parallel processes
    const std::string path =
        ::testing::TempDir() + "/fluidsurf_vdbcheck_" + std::to_string(::getpid()) + ".vdb";
    openvdb::io::File f(path);
    f.setCompression(compression);
    f.write(grids);
    f.close();
    std::ifstream in(path, std::ios::binary);
    std::ostringstream all;
    all << in.rdbuf();
    std::remove(path.c_str());
    return toBytes(all.str());
}

/// Reads .vdb bytes as the file c.vdb through the walk and OpenVDB, counting reads and
/// refusals; a refusal must be one InputError naming the file. An abort or a crash ends the
/// test binary; ASan builds (tools/fuzz) also catch reads out of bounds that do not crash.
struct ReadOrRefuse
{
    size_t read = 0, refused = 0;

    void operator()(const Bytes& b)
    {
        try {
            io_internal::readVdbGrids(b.data(), b.size(), "c.vdb");
            ++read;
        } catch (const InputError& e) {
            EXPECT_EQ(std::string(e.what()).rfind("c.vdb: ", 0), 0u) << e.what();
            ++refused;
        }
    }
};

} // namespace test
} // namespace fluidsurf
