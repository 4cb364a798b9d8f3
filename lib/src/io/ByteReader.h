// ByteReader.h - a bounds-checked cursor over an in-memory file. Every reader goes through it,
// so a truncated or lying file becomes an InputError naming the source and byte offset instead
// of a read past the end. Sizes taken from headers are checked against the bytes that remain
// (checkedCount) before anything is allocated from them.
#pragma once

#include <fluidsurf/Error.h>

#include <cstdint>
#include <cstring>
#include <string>

namespace fluidsurf {
namespace io_internal {

template <typename T> inline T byteSwap(T v)
{
    static_assert(sizeof(T) == 1 || sizeof(T) == 2 || sizeof(T) == 4 || sizeof(T) == 8, "");
    if constexpr (sizeof(T) == 1) {
        return v;
    } else {
        unsigned char b[sizeof(T)];
        std::memcpy(b, &v, sizeof(T));
        for (size_t i = 0; i < sizeof(T) / 2; ++i)
            std::swap(b[i], b[sizeof(T) - 1 - i]);
        std::memcpy(&v, b, sizeof(T));
        return v;
    }
}

/// Load a T stored with the given endianness at p (no alignment needed).
template <typename T> inline T loadAs(const uint8_t* p, bool bigEndian)
{
    T v;
    std::memcpy(&v, p, sizeof(T));
    return bigEndian ? byteSwap(v) : v; // x86-64 and aarch64 hosts are little-endian
}

class ByteReader
{
public:
    ByteReader(const uint8_t* data, size_t size, std::string source)
        : mData(data), mSize(size), mSource(std::move(source))
    {
    }

    const std::string& source() const { return mSource; }
    size_t offset() const { return mPos; }
    size_t size() const { return mSize; }
    size_t remaining() const { return mSize - mPos; }
    bool atEnd() const { return mPos >= mSize; }
    const uint8_t* data() const { return mData; }
    const uint8_t* cursor() const { return mData + mPos; }

    [[noreturn]] void fail(const std::string& what) const { failAt(mPos, what); }
    [[noreturn]] void failAt(size_t offset, const std::string& what) const
    {
        throw InputError(mSource + ": " + what + " (at byte " + std::to_string(offset) + ")");
    }

    void need(size_t n, const char* what) const
    {
        if (n > remaining())
            fail(std::string("file ends while reading ") + what + ": needs " + std::to_string(n) +
                 " bytes, " + std::to_string(remaining()) + " left (truncated or corrupt file?)");
    }

    /// count items of bytesPerItem each must fit in what is left; returns count as size_t.
    size_t checkedCount(uint64_t count, size_t bytesPerItem, const char* what) const
    {
        if (bytesPerItem != 0 && count > remaining() / bytesPerItem)
            fail("header promises " + std::to_string(count) + " " + what + " (" +
                 std::to_string(bytesPerItem) + " bytes each) but only " +
                 std::to_string(remaining()) + " bytes remain (truncated or corrupt file)");
        return size_t(count);
    }

    const uint8_t* take(size_t n, const char* what)
    {
        need(n, what);
        const uint8_t* p = mData + mPos;
        mPos += n;
        return p;
    }

    template <typename T> T read(bool bigEndian, const char* what)
    {
        return loadAs<T>(take(sizeof(T), what), bigEndian);
    }

    void skip(size_t n, const char* what) { take(n, what); }
    void seek(size_t offset)
    {
        if (offset > mSize) failAt(offset, "offset beyond the end of the file");
        mPos = offset;
    }

    /// One text line without its terminator ("\n" or "\r\n"); fails past maxLength bytes, so
    /// a binary file mistaken for text cannot make us scan megabytes for a header line.
    std::string line(const char* what, size_t maxLength = 4096)
    {
        size_t len;
        const size_t start = lineVia([this](size_t i) { return mData[i]; }, what, len, maxLength);
        return std::string(reinterpret_cast<const char*>(mData + start), len);
    }
    /// line() over bytes that at(offset) gives: a cursor over a file not in memory (FileCursor)
    /// keeps its bounds here and finds its lines by the same rules, with the same messages.
    /// Returns where the line starts; len: its length without the terminator.
    template <typename At>
    size_t lineVia(const At& at, const char* what, size_t& len, size_t maxLength = 4096)
    {
        if (atEnd()) fail(std::string("file ends before ") + what);
        size_t start = mPos, end = mPos;
        while (end < mSize && at(end) != '\n') {
            if (end - start > maxLength) failAt(start, std::string("line too long in ") + what);
            ++end;
        }
        mPos = end < mSize ? end + 1 : end;
        len = end - start;
        if (len > 0 && at(start + len - 1) == '\r') --len;
        return start;
    }

private:
    const uint8_t* mData;
    size_t mSize;
    size_t mPos = 0;
    std::string mSource;
};

} // namespace io_internal
} // namespace fluidsurf
