// GridMesh.h - an open n x n grid of unit squares in the xy plane, each cut along a diagonal,
// with a height per point: the flat and bumpy patches of the post-processing tests.
#pragma once

#include <fluidsurf/Mesh.h>

#include <cstdint>

namespace fluidsurf {
namespace test {

/// Points (i, j, height(i, j)) for i, j in [0, n], point j (n + 1) + i; two triangles a square,
/// facing +z.
template <typename Height> TriangleMesh gridMesh(uint32_t n, const Height& height)
{
    TriangleMesh m;
    for (uint32_t j = 0; j <= n; ++j)
        for (uint32_t i = 0; i <= n; ++i)
            m.points.emplace_back(float(i), float(j), float(height(i, j)));
    for (uint32_t j = 0; j < n; ++j)
        for (uint32_t i = 0; i < n; ++i) {
            const uint32_t a = j * (n + 1) + i;
            m.triangles.push_back({a, a + 1, a + n + 2});
            m.triangles.push_back({a, a + n + 2, a + n + 1});
        }
    return m;
}

} // namespace test
} // namespace fluidsurf
