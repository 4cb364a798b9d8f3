// ProcessMemoryTest.cc - the loader's symbol tables released (tools/cli/ProcessMemory): their
// pages leave the process, and the libraries still bind and run afterwards.
#include "cli/ProcessMemory.h"

#include <gtest/gtest.h>
#include <openvdb/io/Stream.h>
#include <openvdb/openvdb.h>

#include <dlfcn.h>
#include <elf.h>
#include <link.h>

#include <cstdint>
#include <cstring>
#include <fstream>
#include <sstream>
#include <string>

namespace {

/// The address of libopenvdb's dynamic symbol table, read from its own .dynamic.
uintptr_t openvdbSymbolTable()
{
    uintptr_t symtab = 0;
    dl_iterate_phdr(
        [](dl_phdr_info* info, size_t, void* out) {
            if (!info->dlpi_name || !std::strstr(info->dlpi_name, "libopenvdb.so")) {
                return 0;
            }
            for (int i = 0; i < info->dlpi_phnum; ++i)
                if (info->dlpi_phdr[i].p_type == PT_DYNAMIC)
                    for (auto* d = reinterpret_cast<const ElfW(Dyn)*>(info->dlpi_addr +
                                                                      info->dlpi_phdr[i].p_vaddr);
                         d->d_tag != DT_NULL; ++d)
                        if (d->d_tag == DT_SYMTAB) *static_cast<uintptr_t*>(out) = d->d_un.d_ptr;
            return 1;
        },
        &symtab);
    return symtab;
}

/// Resident KiB of the mapping that holds address `at` (/proc/self/smaps), -1 if none does.
long residentKiB(uintptr_t at)
{
    std::ifstream smaps("/proc/self/smaps");
    std::string line;
    bool inside = false;
    while (std::getline(smaps, line)) {
        unsigned long begin = 0, end = 0;
        char dash = 0;
        std::istringstream head(line);
        if (line.find(':') == std::string::npos || line.find(' ') < line.find(':')) {
            head >> std::hex >> begin >> dash >> end;
            if (dash == '-') inside = at >= begin && at < end;
            continue;
        }
        if (inside && line.rfind("Rss:", 0) == 0) return std::stol(line.substr(4));
    }
    return -1;
}

} // namespace

TEST(ProcessMemory, LoaderTablesLeaveTheProcessAndTheLibrariesStillBind)
{
    const uintptr_t symtab = openvdbSymbolTable();
    ASSERT_NE(symtab, 0u) << "this test reads libopenvdb's symbol table";
    const long before = residentKiB(symtab);
    ASSERT_GT(before, 0);
    // (Debian 12's libopenvdb: some 25 MiB, bound at start-up)
    const size_t advised = fluidsurf::cli::releaseLoaderTables();
    const long after = residentKiB(symtab);
    std::cout << "libopenvdb's symbol tables resident: " << before << " KiB -> " << after
              << " KiB (" << advised / 1024 << " KiB advised over all objects)\n";
    EXPECT_GE(advised / 1024, size_t(before) / 2);
    EXPECT_LT(after, before / 4);

    // the libraries still work: a symbol looked up by name, and OpenVDB's calls made for the
    // first time here (bound now, through the released tables), with a grid round trip
    EXPECT_NE(dlsym(RTLD_DEFAULT, "_ZN7openvdb5v10_010initializeEv"), nullptr);
    openvdb::initialize();
    openvdb::FloatGrid::Ptr grid = openvdb::FloatGrid::create(-1.f);
    grid->setName("released");
    for (int i = 0; i < 100; ++i)
        grid->tree().setValue(openvdb::Coord(i, 2 * i, -i), float(i));
    std::stringstream bytes;
    {
        openvdb::io::Stream out(static_cast<std::ostream&>(bytes));
        out.write({grid});
    }
    openvdb::io::Stream in(static_cast<std::istream&>(bytes));
    const openvdb::GridPtrVecPtr grids = in.getGrids();
    ASSERT_EQ(grids->size(), 1u);
    const auto back = openvdb::gridPtrCast<openvdb::FloatGrid>((*grids)[0]);
    ASSERT_TRUE(back);
    EXPECT_EQ(back->getName(), "released");
    EXPECT_EQ(back->activeVoxelCount(), 100u);
    for (int i = 0; i < 100; ++i)
        EXPECT_EQ(back->tree().getValue(openvdb::Coord(i, 2 * i, -i)), float(i));
    EXPECT_EQ(back->tree().getValue(openvdb::Coord(1, 1, 1)), -1.f);
}
