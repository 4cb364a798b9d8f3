// Frame patterns: the three spellings, padding, folder scans and range parsing.
#include "TestData.h"

#include <fluidsurf/FramePattern.h>

using namespace fluidsurf;
using namespace fluidsurf::test;

TEST(FramePattern, Spellings)
{
    EXPECT_EQ(FramePattern("a/f_{:04}.bgeo").frame(7), "a/f_0007.bgeo");
    EXPECT_EQ(FramePattern("f_{}.vtk").frame(123), "f_123.vtk");
    EXPECT_EQ(FramePattern("f_####.ply").frame(12), "f_0012.ply");
    EXPECT_EQ(FramePattern("f_%03d.xyz").frame(5), "f_005.xyz");
    EXPECT_EQ(FramePattern("f_%d.xyz").frame(12345), "f_12345.xyz");
    EXPECT_FALSE(FramePattern("plain.bgeo").isSequence());
    EXPECT_FALSE(FramePattern("dir_{:04}/plain.bgeo").isSequence())
        << "only the file name holds a pattern";
    EXPECT_THROW(FramePattern("f_{:x}.bgeo"), ValueError);
    EXPECT_THROW(FramePattern("f_%s.bgeo"), ValueError);
}

TEST(FramePattern, ExistingFramesAndRanges)
{
    TempDir dir;
    for (const char* n :
         {"f_0001.xyz", "f_0003.xyz", "f_0010.xyz", "f_12.xyz", "g_0002.xyz", "f_0004.xyz.bak"})
        writeFile(dir.path(n), "");
    EXPECT_EQ(FramePattern(dir.path("f_{:04}.xyz")).existingFrames(), (std::vector<int>{1, 3, 10}));
    EXPECT_EQ(parseFrameRange("3-6"), (std::vector<int>{3, 4, 5, 6}));
    EXPECT_EQ(parseFrameRange("9"), (std::vector<int>{9}));
    EXPECT_THROW(parseFrameRange("6-3"), ValueError);
    EXPECT_THROW(parseFrameRange("a-b"), ValueError);
}
