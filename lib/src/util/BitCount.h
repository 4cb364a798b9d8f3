// BitCount.h - set bits of three words at once, inline: the build targets baseline x86-64, which
// has no POPCNT, so __builtin_popcountll is a call into libgcc (2% of the instructions of a raw
// reconstruction, most of them in marching cubes' vertex numbers, three calls a lookup).
#pragma once

#include <cstdint>

namespace fluidsurf {
namespace util {

/// Per 4-bit group of x, its set bits (0 to 4).
inline uint64_t nibbleBits(uint64_t x)
{
    x -= x >> 1 & 0x5555555555555555ull;                                   // per 2 bits: 0 to 2
    return (x & 0x3333333333333333ull) + (x >> 2 & 0x3333333333333333ull); // per 4: 0 to 4
}

/// The set bits of a, b and c together (the three counts' groups add without carries: at most
/// 12 a nibble, 24 a byte, 192 in all).
inline uint32_t bitCount3(uint64_t a, uint64_t b, uint64_t c)
{
    uint64_t s = nibbleBits(a) + nibbleBits(b) + nibbleBits(c);
    s = (s & 0x0F0F0F0F0F0F0F0Full) + (s >> 4 & 0x0F0F0F0F0F0F0F0Full);
    return uint32_t(s * 0x0101010101010101ull >> 56);
}

} // namespace util
} // namespace fluidsurf
