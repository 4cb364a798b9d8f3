// Polygon.h - a face of more than three corners (OBJ, PLY) as triangles.
#pragma once

#include <cstddef>
#include <cstdint>

namespace fluidsurf {
namespace io_internal {

/// emit(a, b, c) for each of the n - 2 triangles of the polygon f[0..n), in its winding, as a
/// zig-zag strip rather than a fan: a fan gives its first corner an edge to every other corner
/// (a 1,000-gon's hub has valence 1,000, and OpenMesh's collapse checks cost the square of it:
/// 34 s for a 1,000-sided prism), the strip at most four. Triangles and quads come out exactly
/// as the fan makes them: (0, 1, 2), then (0, 2, 3).
template <typename Emit> void triangulatePolygon(const uint32_t* f, size_t n, Emit&& emit)
{
    const auto corner = [&](size_t i) { return f[(i + 1) % n]; }; // the strip starts at f[1]
    size_t lo = 0, hi = n - 1;
    for (bool front = true; hi - lo >= 2; front = !front) {
        if (front) {
            emit(corner(hi), corner(lo), corner(lo + 1));
            ++lo;
        } else {
            emit(corner(hi), corner(lo), corner(hi - 1));
            --hi;
        }
    }
}

} // namespace io_internal
} // namespace fluidsurf
