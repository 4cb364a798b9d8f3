// BigEndian.h - values appended to a writer's block of bytes in big-endian order, as legacy VTK
// files hold them (the mesh and particle writers).
#pragma once

#include <cstddef>
#include <cstdint>
#include <cstring>
#include <string>

namespace fluidsurf {
namespace io_internal {

/// A 4-byte value's bits.
template <typename T> uint32_t bitsOf(T v)
{
    static_assert(sizeof(T) == 4, "a 4-byte value");
    uint32_t b;
    std::memcpy(&b, &v, 4);
    return b;
}

/// n (at most 4) 32-bit values, each big-endian.
inline void appendBigEndian(std::string& s, const uint32_t* bits, size_t n)
{
    char buf[16];
    for (size_t k = 0; k < n; ++k) {
        const uint32_t b = __builtin_bswap32(bits[k]);
        std::memcpy(buf + 4 * k, &b, 4);
    }
    s.append(buf, 4 * n);
}

inline void appendBigEndian64(std::string& s, uint64_t v)
{
    const uint64_t b = __builtin_bswap64(v);
    char buf[8];
    std::memcpy(buf, &b, 8);
    s.append(buf, 8);
}

} // namespace io_internal
} // namespace fluidsurf
