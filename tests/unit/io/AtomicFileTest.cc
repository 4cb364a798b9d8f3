// AtomicFileTest.cc - outputs of one frame appear together or not at all; temporaries that a
// killed run left behind are removed by a later run, and only those; names and targets that
// could not be written are refused before a byte is.
#include "TestData.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/io/AtomicFile.h>

#include "io/StreamFile.h"
#include "io/Temporaries.h"

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <dirent.h>
#include <fcntl.h>
#include <signal.h>
#include <sys/file.h>
#include <sys/stat.h>
#include <unistd.h>

#include <ctime>

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

/// A file's modification time set seconds ago.
void age(const std::string& path, double seconds)
{
    struct timespec times[2];
    ::clock_gettime(CLOCK_REALTIME, &times[0]);
    times[0].tv_sec -= time_t(seconds);
    times[1] = times[0];
    ASSERT_EQ(::utimensat(AT_FDCWD, path.c_str(), times, 0), 0);
}

// A temporary is stale only when nobody holds its lock and it has not been touched for the
// given age. A PID says nothing: a live run in another PID namespace (a container) or on another
// host sharing the folder has a PID that is not running here, and its temporary was deleted
// under it (issue 63).
TEST(AtomicFile, RemovesOnlyProvablyStaleTemporaries)
{
    const test::TempDir dir;
    pid_t dead = 4000000; // a PID that runs no process here
    while (dead > 2 && (::kill(dead, 0) == 0 || errno != ESRCH))
        --dead;
    const std::string stale = ".fluidsurf-0123456789ab.obj", legacy = ".fluidsurf-tmp-7-3.f.obj",
                      otherNamespace = ".fluidsurf-tmp-" + std::to_string(dead) + "-1.f.vdb",
                      fresh = ".fluidsurf-zyxwvutsrqpo.ply", notOurs = ".fluidsurf-x.obj",
                      user = "fluidsurf-0123456789ab.obj";
    for (const std::string& name : {stale, legacy, otherNamespace, fresh, notOurs, user}) {
        test::writeFile(dir.path(name), "bytes");
        if (name != fresh) age(dir.path(name), 7200);
    }
    // the live run elsewhere holds its lock (flock: another open file description conflicts,
    // in this process as in any other)
    const int held = ::open(dir.path(otherNamespace).c_str(), O_RDONLY);
    ASSERT_GE(held, 0);
    ASSERT_EQ(::flock(held, LOCK_EX), 0);
    EXPECT_EQ(io_internal::removeStaleTemporaries(dir.path(), 3600), 2);
    EXPECT_FALSE(test::fileExists(dir.path(stale)));
    EXPECT_FALSE(test::fileExists(dir.path(legacy)));
    EXPECT_TRUE(test::fileExists(dir.path(otherNamespace))) << "a locked temporary was removed";
    EXPECT_TRUE(test::fileExists(dir.path(fresh))) << "a recent temporary was removed";
    EXPECT_TRUE(test::fileExists(dir.path(notOurs)));
    EXPECT_TRUE(test::fileExists(dir.path(user)));
    ::close(held); // the run ended without renaming: now it is stale
    EXPECT_EQ(io_internal::removeStaleTemporaries(dir.path(), 3600), 1);
    EXPECT_FALSE(test::fileExists(dir.path(otherNamespace)));
}

// A live AtomicFile's temporary survives another run's sweep even at age 0: its lock is held.
TEST(AtomicFile, ALiveTemporaryIsLocked)
{
    const test::TempDir dir;
    io::AtomicFile file(dir.path("frame.bgeo.gz"));
    const std::string temp = file.tempPath();
    EXPECT_TRUE(io_internal::isTemporaryName(temp.substr(temp.find_last_of('/') + 1))) << temp;
    EXPECT_EQ(temp.substr(temp.size() - 8), ".bgeo.gz"); // the format is still in the name
    EXPECT_EQ(io_internal::removeStaleTemporaries(dir.path(), 0), 0);
    EXPECT_TRUE(test::fileExists(temp));
}

// Temporaries are short whatever the target's name: a valid 255-byte name (the most most file
// systems allow) failed after the work when the temporary's name was the target's plus 20.
TEST(AtomicFile, TheLongestValidNameCanBeWritten)
{
    const test::TempDir dir;
    const std::string name = std::string(251, 'n') + ".obj";
    ASSERT_EQ(name.size(), 255u);
    io::writeFileAtomic(dir.path(name), "mesh", 4);
    EXPECT_EQ(test::readFileBytes(dir.path(name)), "mesh");
    EXPECT_EQ(listFolder(dir.path()).size(), 1u);
}

// A name that is not a regular file is never replaced; a link to a file stays a link and the
// file it names gets the bytes.
TEST(AtomicFile, RefusesNonRegularTargetsAndFollowsLinks)
{
    const test::TempDir dir;
    ASSERT_EQ(::mkdir(dir.path("folder.obj").c_str(), 0755), 0);
    ASSERT_EQ(::mkfifo(dir.path("fifo.obj").c_str(), 0644), 0);
    for (const char* name : {"folder.obj", "fifo.obj"}) {
        try {
            io::writeFileAtomic(dir.path(name), "x", 1);
            ADD_FAILURE() << name << " was replaced";
        } catch (const OutputError& e) {
            EXPECT_NE(std::string(e.what()).find("not a regular file"), std::string::npos)
                << e.what();
        }
    }
    struct stat st;
    ASSERT_EQ(::lstat(dir.path("fifo.obj").c_str(), &st), 0);
    EXPECT_TRUE(S_ISFIFO(st.st_mode));
    test::writeFile(dir.path("real.obj"), "old");
    ASSERT_EQ(::symlink("real.obj", dir.path("link.obj").c_str()), 0);
    io::writeFileAtomic(dir.path("link.obj"), "new", 3);
    ASSERT_EQ(::lstat(dir.path("link.obj").c_str(), &st), 0);
    EXPECT_TRUE(S_ISLNK(st.st_mode)) << "the link was replaced by a file";
    EXPECT_EQ(test::readFileBytes(dir.path("real.obj")), "new");
    EXPECT_THROW(io::writeFileAtomic(dir.path("a") + std::string(1, '\0') + "b.obj", "x", 1),
                 OutputError);
    EXPECT_FALSE(test::fileExists(dir.path("a")));
}

} // namespace
} // namespace fluidsurf
