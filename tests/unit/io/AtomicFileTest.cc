// AtomicFileTest.cc - outputs of one frame appear together or not at all, and temporaries that
// a killed run left behind are removed by the next run in the folder.
#include "TestData.h"

#include <fluidsurf/io/AtomicFile.h>

#include <gtest/gtest.h>

#include <dirent.h>
#include <signal.h>
#include <unistd.h>

#include <cerrno>
#include <string>
#include <vector>

namespace fluidsurf {
namespace {

std::vector<std::string> listFolder(const std::string& path)
{
    std::vector<std::string> names;
    if (DIR* d = ::opendir(path.c_str())) {
        while (const dirent* e = ::readdir(d))
            if (std::string(e->d_name) != "." && std::string(e->d_name) != "..")
                names.push_back(e->d_name);
        ::closedir(d);
    }
    return names;
}

TEST(OutputGroup, AllOrNothing)
{
    const test::TempDir dir;
    test::writeFile(dir.path("a.obj"), "old a");
    test::writeFile(dir.path("b.vdb"), "old b");
    {
        io::OutputGroup group;
        const std::string a = group.add(dir.path("a.obj")), b = group.add(dir.path("b.vdb"));
        EXPECT_EQ(a.substr(a.size() - 4), ".obj"); // the extension still names the format
        EXPECT_EQ(b.substr(b.size() - 4), ".vdb");
        io::writeFileAtomic(a, "new a", 5);
        io::writeFileAtomic(b, "new b", 5);
        // No commit: an error or a stop came between the writes and the renames.
    }
    EXPECT_EQ(test::readFileBytes(dir.path("a.obj")), "old a");
    EXPECT_EQ(test::readFileBytes(dir.path("b.vdb")), "old b");
    EXPECT_EQ(listFolder(dir.path()).size(), 2u) << "temporaries left behind";
    {
        io::OutputGroup group;
        io::writeFileAtomic(group.add(dir.path("a.obj")), "new a", 5);
        io::writeFileAtomic(group.add(dir.path("b.vdb")), "new b", 5);
        group.commit();
    }
    EXPECT_EQ(test::readFileBytes(dir.path("a.obj")), "new a");
    EXPECT_EQ(test::readFileBytes(dir.path("b.vdb")), "new b");
    EXPECT_EQ(listFolder(dir.path()).size(), 2u);
}

TEST(AtomicFile, RemovesTemporariesOfKilledRuns)
{
    const test::TempDir dir;
    // A PID that runs no process, and one that does (this one).
    pid_t dead = 4000000;
    while (dead > 2 && (::kill(dead, 0) == 0 || errno != ESRCH))
        --dead;
    const std::string stale = ".fluidsurf-tmp-" + std::to_string(dead) + "-3.frame.obj";
    const std::string live = ".fluidsurf-tmp-" + std::to_string(::getpid()) + "-99.frame.vdb";
    test::writeFile(dir.path(stale), "left by a killed run");
    test::writeFile(dir.path(live), "being written");
    test::writeFile(dir.path(".fluidsurf-tmp-x.obj"), "not ours: no PID");
    io::writeFileAtomic(dir.path("out.obj"), "x", 1);
    EXPECT_FALSE(test::fileExists(dir.path(stale)));
    EXPECT_TRUE(test::fileExists(dir.path(live)));
    EXPECT_TRUE(test::fileExists(dir.path(".fluidsurf-tmp-x.obj")));
    EXPECT_EQ(test::readFileBytes(dir.path("out.obj")), "x");
}

} // namespace
} // namespace fluidsurf
