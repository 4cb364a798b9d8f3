// AtomicFileTest.cc - outputs of one frame appear together or not at all, and temporaries that
// a killed run left behind are removed by the next run in the folder.
#include "TestData.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/io/AtomicFile.h>

#include "io/StreamFile.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

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

/// Item i's text: its number and a run of letters whose length varies, so that chunks and blocks
/// end in the middle of nothing in particular.
void itemText(std::string& out, size_t i)
{
    out += std::to_string(i);
    out.append(i % 23, char('a' + i % 26));
    out += '\n';
}

// writeItems encodes a block on the other threads while it writes the one before: the file must
// hold every item once, in order, whatever the thread count, across several blocks (262,144 items
// each) and past the size at which the disk is asked to start writing (StreamFile::kWriteBack).
TEST(StreamFile, ItemsOfManyBlocksComeOutInOrderForAnyThreadCount)
{
    const test::TempDir dir;
    const size_t count = 3 * 262144 + 12345;
    std::string expected = "header\n";
    for (size_t i = 0; i < count; ++i)
        itemText(expected, i);
    ASSERT_GT(expected.size(), io::StreamFile::kWriteBack); // the write-back is reached
    for (int threads : {1, 2, 5}) {
        const tbb::global_control limit(tbb::global_control::max_allowed_parallelism, threads);
        const std::string path = dir.path("items.txt");
        io::StreamFile out(path);
        out.write("header\n");
        io::writeItems(out, count, 16, itemText);
        out.commit();
        EXPECT_TRUE(test::readFileBytes(path) == expected) << threads << " threads";
    }
    EXPECT_EQ(listFolder(dir.path()).size(), 1u) << "temporaries left behind";
}

// An item that throws in the middle (a block being encoded while another is written): the error
// comes out, and neither the target nor a temporary is left.
TEST(StreamFile, AnErrorWhileEncodingLeavesNoFile)
{
    const test::TempDir dir;
    const size_t count = 2 * 262144 + 10;
    EXPECT_THROW(
        {
            io::StreamFile out(dir.path("items.txt"));
            io::writeItems(out, count, 16, [](std::string& s, size_t i) {
                if (i == 262144 + 5) throw ValueError("item 262149");
                itemText(s, i);
            });
            out.commit();
        },
        ValueError);
    EXPECT_TRUE(listFolder(dir.path()).empty());
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
