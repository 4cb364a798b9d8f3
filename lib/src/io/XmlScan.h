// XmlScan.h - a minimal scanner for the tag structure of VTK XML files. VTK XML is machine
// written and flat; a full XML library is not in the dependency list and would also choke on the
// raw binary bytes of <AppendedData>, which this scanner stops in front of.
#pragma once

#include "io/ByteReader.h"

#include <map>
#include <string>

namespace fluidsurf {
namespace io_internal {

struct XmlTag
{
    std::string name; ///< without '/' for end tags
    std::map<std::string, std::string> attrs;
    bool isEnd = false;        ///< </name>
    bool selfClosing = false;  ///< <name ... />
    size_t begin = 0, end = 0; ///< byte range of "<...>" in the buffer
};

/// Next element tag at or after the reader's position, skipping text, comments, <?...?> and
/// <!...>; false at the end of the buffer. The reader is left just after the tag.
bool nextXmlTag(ByteReader& in, XmlTag& tag);

/// Attribute value or fallback.
inline std::string attr(const XmlTag& t, const std::string& key, const std::string& fallback = "")
{
    auto it = t.attrs.find(key);
    return it == t.attrs.end() ? fallback : it->second;
}

/// Decode base64 quartet by quartet, so concatenated separately padded runs (VTK encodes the
/// block header and the data separately) decode as one byte stream. Whitespace is skipped.
/// Stops after maxBytes output bytes (decoding whole quartets); returns false on a bad char.
bool decodeBase64(const uint8_t* text, size_t length, std::string& out, size_t maxBytes,
                  size_t* charsUsed = nullptr);

} // namespace io_internal
} // namespace fluidsurf
