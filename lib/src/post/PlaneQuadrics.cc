// PlaneQuadrics.cc - see PlaneQuadrics.h. The vector types here never cross a call (the wide
// path is one function compiled for its target), so GCC's note that their ABI differs without
// AVX does not apply.
#pragma GCC diagnostic ignored "-Wpsabi"

#include "post/PlaneQuadrics.h"

#include "util/Lanes.h"

#include <fluidsurf/Error.h>

#include <algorithm>

namespace fluidsurf {
namespace post {
namespace {

using Tri = std::array<uint32_t, 3>;

/// Vertex v's quadric, one corner at a time.
Quadric planesAround(const Vec3d* points, const std::vector<Tri>& triangles,
                     const VertexTriangles& around, uint32_t first, uint32_t v)
{
    Quadric q{};
    for (uint32_t i = around.start[v - first]; i < around.start[v - first + 1]; ++i) {
        const Tri& t = triangles[around.tris[i]];
        const Vec3d n = sideCross(points, t);
        const double len = n.length();
        if (len > 0) q += Quadric::plane(n / len, points[t[0]] - points[v], len / 2);
    }
    return q;
}

/// planesAround four vertices at a time, one a lane of AVX registers, where the CPU has AVX2:
/// the same operations in the same order on each lane (Vec3d's cross product, length and
/// division, Quadric::plane; no FMA in this target). A lane past its vertex's last triangle,
/// or at a triangle without area, adds +0 to each sum, which leaves it as it is: no sum here
/// is -0 (each starts at +0, and +0 + -0 = +0).
__attribute__((target("avx2"))) void planesAroundWide(const Vec3d* points,
                                                      const std::vector<Tri>& triangles,
                                                      const VertexTriangles& around, uint32_t first,
                                                      uint32_t begin, uint32_t end,
                                                      PackedQuadric* out)
{
    using V = util::WideDoubles;
    typedef long long Mask __attribute__((vector_size(32)));
    uint32_t v = begin;
    for (; v + 4 <= end; v += 4) {
        uint32_t from[4], count[4], most = 0;
        V px, py, pz;
        for (int l = 0; l < 4; ++l) {
            from[l] = around.start[v + l - first];
            count[l] = around.start[v + l - first + 1] - from[l];
            most = std::max(most, count[l]);
            px[l] = points[v + l][0], py[l] = points[v + l][1], pz[l] = points[v + l][2];
        }
        BasicQuadric<V> q{};
        for (uint32_t k = 0; k < most; ++k) {
            V c[3][3] = {}; // the triangles' corners, c[corner][axis]
            Mask in{};
            for (int l = 0; l < 4; ++l) {
                const bool has = k < count[l];
                in[l] = has ? -1 : 0;
                const Tri& t = triangles[has ? around.tris[from[l] + k] : 0]; // (any, if not)
                for (int j = 0; j < 3; ++j)
                    for (int a = 0; a < 3; ++a)
                        c[j][a][l] = points[t[j]][a];
            }
            const V e1x = c[1][0] - c[0][0], e1y = c[1][1] - c[0][1], e1z = c[1][2] - c[0][2];
            const V e2x = c[2][0] - c[0][0], e2y = c[2][1] - c[0][1], e2z = c[2][2] - c[0][2];
            const V nx = e1y * e2z - e1z * e2y, ny = e1z * e2x - e1x * e2z,
                    nz = e1x * e2y - e1y * e2x;
            const V len = __builtin_ia32_sqrtpd256(nx * nx + ny * ny + nz * nz);
            const Mask use = in & (len > 0);
            const V ux = nx / len, uy = ny / len, uz = nz / len;
            const V dx = c[0][0] - px, dy = c[0][1] - py, dz = c[0][2] - pz;
            const V w = len / 2, d = -(ux * dx + uy * dy + uz * dz);
            const V zero{};
            auto add = [&](V& sum, const V& term) { sum += use ? term : zero; };
            add(q.a00, w * ux * ux), add(q.a01, w * ux * uy), add(q.a02, w * ux * uz);
            add(q.a11, w * uy * uy), add(q.a12, w * uy * uz), add(q.a22, w * uz * uz);
            add(q.b0, w * d * ux), add(q.b1, w * d * uy), add(q.b2, w * d * uz);
            add(q.c, w * d * d), add(q.w, w);
        }
        for (int l = 0; l < 4; ++l)
            out[v + l] = PackedQuadric::pack({q.a00[l], q.a01[l], q.a02[l], q.a11[l], q.a12[l],
                                              q.a22[l], q.b0[l], q.b1[l], q.b2[l], q.c[l], q.w[l]});
    }
    for (; v < end; ++v)
        out[v] = PackedQuadric::pack(planesAround(points, triangles, around, first, v));
}

} // namespace

void planeQuadrics(const Vec3d* points, const std::vector<Tri>& triangles,
                   const VertexTriangles& around, uint32_t first, uint32_t begin, uint32_t end,
                   PackedQuadric* out, int lanes)
{
    const int wide = util::doubleRegisterLanes() == 4 ? 4 : 1;
    if (lanes == 0) lanes = wide;
    if (lanes != 1 && lanes != 4) throw ValueError("planeQuadrics: 1 or 4 vertices at a time");
    if (lanes > wide) throw ValueError("planeQuadrics: 4 vertices at a time need a CPU with AVX2");
    if (lanes == 4) {
        planesAroundWide(points, triangles, around, first, begin, end, out);
        return;
    }
    for (uint32_t v = begin; v < end; ++v)
        out[v] = PackedQuadric::pack(planesAround(points, triangles, around, first, v));
}

} // namespace post
} // namespace fluidsurf
