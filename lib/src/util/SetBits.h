// SetBits.h - for each 8-bit mask, the positions of its set bits in order, and how many: the
// table that packs a register's chosen lanes to its front (a compress, which AVX2 lacks) with one
// permute, or that lists the chosen lanes' numbers at once (classification's live groups, the
// field's row selection).
#pragma once

#include <cstdint>

namespace fluidsurf {
namespace util {

struct SetBits
{
    int32_t positions[256][8]; ///< mask m's set bits, lowest first (the rest 0)
    uint8_t count[256];
};

constexpr SetBits setBits()
{
    SetBits t{};
    for (unsigned m = 0; m < 256; ++m)
        for (int l = 0; l < 8; ++l)
            if (m >> l & 1) t.positions[m][t.count[m]++] = l;
    return t;
}

inline constexpr SetBits kSetBits = setBits();

} // namespace util
} // namespace fluidsurf
