// FramePattern.cc - parsing of the three pattern spellings and folder scanning.
#include <fluidsurf/Error.h>
#include <fluidsurf/FramePattern.h>

#include <algorithm>
#include <cctype>
#include <dirent.h>

namespace fluidsurf {

FramePattern::FramePattern(const std::string& path) : mPath(path)
{
    // Only the file name may hold the pattern.
    const size_t slash = path.find_last_of('/');
    const size_t nameStart = slash == std::string::npos ? 0 : slash + 1;
    size_t at = std::string::npos, len = 0;
    if (size_t b = path.find('{', nameStart); b != std::string::npos) {
        const size_t e = path.find('}', b);
        if (e == std::string::npos)
            throw ValueError("frame pattern '" + path + "': '{' without '}'");
        const std::string spec = path.substr(b + 1, e - b - 1);
        if (spec.empty())
            mWidth = 0;
        else if (spec.size() >= 3 && spec[0] == ':' && spec[1] == '0' &&
                 std::all_of(spec.begin() + 2, spec.end(), ::isdigit))
            mWidth = std::stoi(spec.substr(2));
        else if (spec.size() >= 2 && spec[0] == ':' &&
                 std::all_of(spec.begin() + 1, spec.end(), ::isdigit))
            mWidth = std::stoi(spec.substr(1));
        else
            throw ValueError("frame pattern '" + path + "': unsupported '{" + spec +
                             "}' (use {} or {:04})");
        at = b;
        len = e - b + 1;
    } else if (size_t h = path.find('#', nameStart); h != std::string::npos) {
        size_t e = h;
        while (e < path.size() && path[e] == '#')
            ++e;
        mWidth = int(e - h);
        at = h;
        len = e - h;
    } else if (size_t p = path.find('%', nameStart); p != std::string::npos) {
        size_t e = p + 1;
        while (e < path.size() && std::isdigit(uint8_t(path[e])))
            ++e;
        if (e >= path.size() || path[e] != 'd')
            throw ValueError("frame pattern '" + path + "': unsupported '%' spec (use %04d or %d)");
        const std::string w = path.substr(p + 1, e - p - 1);
        mWidth = w.empty() ? 0 : std::stoi(w);
        at = p;
        len = e - p + 1;
    }
    if (at == std::string::npos) return;
    if (mWidth > 12)
        throw ValueError("frame pattern '" + path + "': width " + std::to_string(mWidth) +
                         " is too large");
    mIsSequence = true;
    mPrefix = path.substr(0, at);
    mSuffix = path.substr(at + len);
}

std::string FramePattern::frame(int number) const
{
    if (!mIsSequence) return mPath;
    std::string digits = std::to_string(number < 0 ? -number : number);
    if (int(digits.size()) < mWidth) digits.insert(0, size_t(mWidth) - digits.size(), '0');
    return mPrefix + (number < 0 ? "-" : "") + digits + mSuffix;
}

std::vector<int> FramePattern::existingFrames() const
{
    std::vector<int> frames;
    if (!mIsSequence) return frames;
    const size_t slash = mPrefix.find_last_of('/');
    const std::string dir = slash == std::string::npos ? "." : mPrefix.substr(0, slash + 1);
    const std::string namePrefix = slash == std::string::npos ? mPrefix : mPrefix.substr(slash + 1);
    DIR* d = ::opendir(dir.c_str());
    if (!d) return frames;
    while (dirent* e = ::readdir(d)) {
        const std::string n = e->d_name;
        if (n.size() <= namePrefix.size() + mSuffix.size()) continue;
        if (n.compare(0, namePrefix.size(), namePrefix) != 0) continue;
        if (n.compare(n.size() - mSuffix.size(), mSuffix.size(), mSuffix) != 0) continue;
        const std::string mid =
            n.substr(namePrefix.size(), n.size() - namePrefix.size() - mSuffix.size());
        if (mid.empty() || mid.size() > 9 || !std::all_of(mid.begin(), mid.end(), ::isdigit))
            continue;
        if (mWidth > 0 && int(mid.size()) < mWidth) continue;
        const int f = std::stoi(mid);
        if (frame(f).substr(frame(f).size() - n.size()) == n) frames.push_back(f);
    }
    ::closedir(d);
    std::sort(frames.begin(), frames.end());
    return frames;
}

std::vector<int> parseFrameRange(const std::string& range)
{
    auto parse = [&](const std::string& s) {
        if (s.empty() || s.size() > 9 || !std::all_of(s.begin(), s.end(), ::isdigit))
            throw ValueError("bad frame range '" + range + "' (expected A-B, e.g. 1-100)");
        return std::stoi(s);
    };
    const size_t dash = range.find('-');
    const int a = parse(range.substr(0, dash));
    const int b = dash == std::string::npos ? a : parse(range.substr(dash + 1));
    if (b < a) throw ValueError("bad frame range '" + range + "': end before start");
    std::vector<int> frames;
    for (int f = a; f <= b; ++f)
        frames.push_back(f);
    return frames;
}

} // namespace fluidsurf
