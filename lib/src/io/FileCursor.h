// FileCursor.h - ByteReader's cursor over a file that is not in memory: text lines come through
// a small window, binary records straight from the file into their arrays on all threads. A
// reader written for both (legacy VTK) gives the same values and the same messages either way,
// since the bounds, offsets and messages are ByteReader's own.
#pragma once

#include "io/ByteReader.h"
#include "io/FileBuffer.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <string>
#include <vector>

namespace fluidsurf {
namespace io_internal {

class FileCursor
{
public:
    FileCursor(const OpenFile& file, std::string source)
        : mFile(file), mBounds(nullptr, size_t(file.size()), std::move(source))
    {
    }

    const std::string& source() const { return mBounds.source(); }
    size_t offset() const { return mBounds.offset(); }
    size_t size() const { return mBounds.size(); }
    size_t remaining() const { return mBounds.remaining(); }
    bool atEnd() const { return mBounds.atEnd(); }

    [[noreturn]] void fail(const std::string& what) const { mBounds.fail(what); }
    [[noreturn]] void failAt(size_t offset, const std::string& what) const
    {
        mBounds.failAt(offset, what);
    }
    void need(size_t n, const char* what) const { mBounds.need(n, what); }
    size_t checkedCount(uint64_t count, size_t bytesPerItem, const char* what) const
    {
        return mBounds.checkedCount(count, bytesPerItem, what);
    }
    void skip(size_t n, const char* what)
    {
        mBounds.need(n, what);
        mBounds.seek(offset() + n);
    }
    void seek(size_t offset) { mBounds.seek(offset); }
    /// The next n bytes (a header's), valid until the cursor reads again.
    const uint8_t* take(size_t n, const char* what)
    {
        mBounds.need(n, what);
        mWindow.resize(n);
        mFile.readAt(offset(), mWindow.data(), n);
        mWindowStart = offset();
        mBounds.seek(offset() + n);
        return mWindow.data();
    }
    template <typename T> T read(bool bigEndian, const char* what)
    {
        return loadAs<T>(take(sizeof(T), what), bigEndian);
    }

    std::string line(const char* what, size_t maxLength = 4096)
    {
        size_t len;
        const auto at = [this](size_t i) { return byteAt(i); };
        const size_t start = mBounds.lineVia(at, what, len, maxLength);
        std::string text(len, '\0');
        for (size_t i = 0; i < len; ++i)
            text[i] = char(at(start + i));
        return text;
    }

    /// n records of `bytes` each from the cursor on, handed over a slice at a time as
    /// f(first record, records, their bytes) on all threads; the cursor moves past them.
    template <typename F> void records(size_t n, size_t bytes, const char* what, const F& f)
    {
        mBounds.need(n * bytes, what);
        forRecordSlices(mFile, offset(), n, bytes, f);
        mBounds.seek(offset() + n * bytes);
    }

private:
    const OpenFile& mFile;
    ByteReader mBounds; // no bytes: the position, the bounds and the messages
    std::vector<uint8_t> mWindow;
    size_t mWindowStart = 0;

    uint8_t byteAt(size_t i)
    {
        if (i - mWindowStart >= mWindow.size()) {
            // 64 KiB from i on: a header line or a section's keywords, not its values
            mWindow.resize(std::min<size_t>(size_t(1) << 16, size() - i));
            mFile.readAt(i, mWindow.data(), mWindow.size());
            mWindowStart = i;
        }
        return mWindow[i - mWindowStart];
    }
};

/// The same records from a file in memory, for a reader written for both cursors.
template <typename F>
void records(ByteReader& in, size_t n, size_t bytes, const char* what, const F& f)
{
    const uint8_t* p = in.take(n * bytes, what);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, n, 1 << 15),
                      [&](const tbb::blocked_range<size_t>& r) {
                          f(r.begin(), r.size(), p + r.begin() * bytes);
                      });
}
template <typename F>
void records(FileCursor& in, size_t n, size_t bytes, const char* what, const F& f)
{
    in.records(n, bytes, what, f);
}

} // namespace io_internal
} // namespace fluidsurf
