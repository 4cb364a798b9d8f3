// The bounds-checked cursor every binary reader relies on.
#include "io/ByteReader.h"

#include <gtest/gtest.h>

using fluidsurf::InputError;
using fluidsurf::io_internal::ByteReader;

TEST(ByteReader, ReadsBothEndiannessesAndStopsAtTheEnd)
{
    const uint8_t d[] = {0x00, 0x00, 0x01, 0x02, 0x02, 0x01, 0x00, 0x00};
    ByteReader in(d, sizeof(d), "buf");
    EXPECT_EQ(in.read<uint32_t>(true, "a"), 0x102u);
    EXPECT_EQ(in.read<uint32_t>(false, "b"), 0x102u);
    EXPECT_TRUE(in.atEnd());
    EXPECT_THROW(in.read<uint8_t>(false, "c"), InputError);
}

TEST(ByteReader, CheckedCountRejectsHeadersLargerThanTheData)
{
    const uint8_t d[100] = {};
    ByteReader in(d, sizeof(d), "buf");
    EXPECT_EQ(in.checkedCount(8, 12, "points"), 8u);
    try {
        in.checkedCount(uint64_t(1) << 40, 12, "points");
        FAIL() << "no exception";
    } catch (const InputError& e) {
        EXPECT_NE(std::string(e.what()).find("buf: header promises 1099511627776 points"),
                  std::string::npos)
            << e.what();
    }
}

TEST(ByteReader, LinesStripCarriageReturnsAndAreBounded)
{
    const std::string s = "abc\r\ndef\n" + std::string(100, 'x');
    ByteReader in(reinterpret_cast<const uint8_t*>(s.data()), s.size(), "buf");
    EXPECT_EQ(in.line("l"), "abc");
    EXPECT_EQ(in.line("l"), "def");
    EXPECT_THROW(in.line("l", 50), InputError);
}
