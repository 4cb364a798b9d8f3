// FramePattern.h - frame sequences named by a pattern: "fluid_{:04}.bgeo", "fluid_{}.bgeo",
// "fluid_####.bgeo" or "fluid_%04d.bgeo". A path with none of these is a single file.
#pragma once

#include <string>
#include <vector>

namespace fluidsurf {

class FramePattern
{
public:
    /// Parses the pattern; ValueError for a malformed one (e.g. "{:x}").
    explicit FramePattern(const std::string& path);

    bool isSequence() const { return mIsSequence; }
    const std::string& path() const { return mPath; }
    /// The file name of one frame (zero-padded to the pattern's width).
    std::string frame(int number) const;
    /// Frame numbers whose files exist in the pattern's folder, ascending.
    std::vector<int> existingFrames() const;

private:
    std::string mPath, mPrefix, mSuffix;
    int mWidth = 0;
    bool mIsSequence = false;
};

/// "A-B" or "A" → frame numbers; ValueError on a malformed range.
std::vector<int> parseFrameRange(const std::string& range);

} // namespace fluidsurf
