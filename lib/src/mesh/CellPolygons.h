// CellPolygons.h - the polygons of one marching-cubes cell from its 8 corner values, shared by
// the uniform mesher (MarchingCubes.cc) and the adaptive one (adaptive/MeshLevels.cc), so both
// cut a face the same way and their meshes meet without gaps.
//
// On each face, a segment runs from the edge where the walk (counter-clockwise seen from outside
// the cell) enters the inside to the edge where it leaves; the segments chain into closed
// polygons, oriented counter-clockwise seen from outside the fluid. A face with four crossings
// pairs them by the sign of the bilinear saddle value (the asymptotic decider), which both cells
// of a face compute from the same four values. That choice also follows the bilinear function
// itself: a face whose values were sub-sampled bilinearly from a coarser face (the adaptive
// grid's transition faces, thesis Fig. 6.4) is cut into the same pieces on both resolutions.
//
// The GPU mesher (cuda/src/MarchingCubes.cu) compiles this header too (FLUIDSURF_HD), so both
// backends cut a cell the same way.
#pragma once

#include "util/HostDevice.h"

namespace fluidsurf {
namespace mesh {

// Corner n of a cell is at offset (n & 1, n >> 1 & 1, n >> 2 & 1).
constexpr int kCorner[8][3] = {{0, 0, 0}, {1, 0, 0}, {0, 1, 0}, {1, 1, 0},
                               {0, 0, 1}, {1, 0, 1}, {0, 1, 1}, {1, 1, 1}};
// Faces, corners counter-clockwise seen from outside the cell: -x, +x, -y, +y, -z, +z.
constexpr int kFace[6][4] = {{0, 4, 6, 2}, {1, 3, 7, 5}, {0, 1, 5, 4},
                             {2, 6, 7, 3}, {0, 2, 3, 1}, {4, 5, 7, 6}};

// The 12 cell edges: edge (a, b) of adjacent corners has index edgeIndex[a][b]; its lower
// corner and axis locate the grid edge (and so the vertex) it shares with other cells.
struct EdgeTable
{
    int index[8][8] = {};
    int lowCorner[12] = {}, axis[12] = {};
    constexpr EdgeTable()
    {
        int n = 0;
        for (int a = 0; a < 8; ++a)
            for (int b = 0; b < 8; ++b)
                index[a][b] = -1;
        for (int a = 0; a < 8; ++a)
            for (int bit = 0; bit < 3; ++bit) {
                if (a >> bit & 1) continue;
                const int b = a | 1 << bit;
                index[a][b] = index[b][a] = n;
                lowCorner[n] = a, axis[n] = bit;
                ++n;
            }
    }
};
inline constexpr EdgeTable kEdges{};

// Device code cannot index the host arrays above: there the tables come packed into integers
// (4 bits a corner, 16 a face; the first edge of each lower corner, 4 bits each; 4 and 2 bits an
// edge), checked against the arrays at compile time. The host keeps the arrays: the packed
// look-ups cost it 78% more instructions in the polygons.
namespace packed {
FLUIDSURF_HD constexpr int faceCorner(int f, int k)
{
    return f < 4 ? int(0x3762451057312640ull >> (16 * f + 4 * k) & 15)
                 : int(0x67541320u >> (16 * (f - 4) + 4 * k) & 15);
}
/// For corners a, b that differ in one bit: the edges are numbered by lower corner, then axis.
FLUIDSURF_HD constexpr int edgeIndex(int a, int b)
{
    const int low = a & b, d = a ^ b;      // d: the axis' bit
    const int clearBelow = ~low & (d - 1); // the low corner's clear bits below the axis
    return int(0xCBA87530u >> (4 * low) & 15) + (clearBelow & 1) + (clearBelow >> 1 & 1);
}
FLUIDSURF_HD constexpr int edgeLowCorner(int e)
{
    return int(0x654432211000ull >> (4 * e) & 15);
}
FLUIDSURF_HD constexpr int edgeAxis(int e)
{
    return int(0x14A264u >> (2 * e) & 3);
}
} // namespace packed

/// kEdges.index[a][b] on either side.
FLUIDSURF_HD constexpr int edgeIndex(int a, int b)
{
#ifdef __CUDA_ARCH__
    return packed::edgeIndex(a, b);
#else
    return kEdges.index[a][b];
#endif
}

namespace detail {
constexpr bool packedTablesAgree()
{
    for (int f = 0; f < 6; ++f)
        for (int k = 0; k < 4; ++k)
            if (packed::faceCorner(f, k) != kFace[f][k]) return false;
    for (int a = 0; a < 8; ++a)
        for (int b = 0; b < 8; ++b)
            if (kEdges.index[a][b] >= 0 && packed::edgeIndex(a, b) != kEdges.index[a][b])
                return false;
    for (int e = 0; e < 12; ++e)
        if (packed::edgeLowCorner(e) != kEdges.lowCorner[e] ||
            packed::edgeAxis(e) != kEdges.axis[e])
            return false;
    return true;
}
static_assert(packedTablesAgree(), "the packed cell tables differ from kFace / kEdges");
} // namespace detail

// Crossing points are kept off the corners: a corner value of exactly 0 would otherwise put
// several vertices on one point and leave zero-area triangles.
constexpr double kEdgeMargin = 1e-3;

FLUIDSURF_HD constexpr bool inside(float v)
{
    return v < 0;
}

/// A cell's sign pattern, bit n: corner n inside (0 and 255: no crossing).
FLUIDSURF_HD constexpr int cellSignPattern(const float c[8])
{
    int pattern = 0;
    for (int n = 0; n < 8; ++n)
        pattern |= int(inside(c[n])) << n;
    return pattern;
}

/// Where the zero crossing lies on an edge from value a to value b, as a fraction of the edge.
FLUIDSURF_HD inline double crossing(float a, float b)
{
    const double t = double(a) / (double(a) - double(b));
    return t < kEdgeMargin ? kEdgeMargin : 1 - kEdgeMargin < t ? 1 - kEdgeMargin : t; // std::clamp
}

/// The polygons of a cell: next[e] is the edge after crossing edge e on its polygon (-1: e has
/// no crossing), face[e] the cell face (index into kFace) that the segment e -> next[e] lies on.
struct CellPolygons
{
    int next[12], face[12];
    /// A face with four crossings: fanning a polygon there could join two vertices of that face
    /// in both cells of the face (an edge with four triangles); such cells fan around a centre.
    bool ambiguous = false;

    FLUIDSURF_HD explicit CellPolygons(const float c[8]);
    constexpr CellPolygons() : next{}, face{} {}

    /// The polygons of the corners' signs alone (bit n of `pattern`: corner n inside), where no
    /// face has four crossings (those need the values: not called for them). For the table.
    constexpr explicit CellPolygons(int pattern) : next{}, face{}
    {
        float c[8] = {};
        for (int n = 0; n < 8; ++n)
            c[n] = pattern >> n & 1 ? -1.f : 1.f;
        cut(c);
    }

    /// From the corner values (see the constructor).
    FLUIDSURF_HD constexpr void cut(const float c[8])
    {
        for (int e = 0; e < 12; ++e)
            next[e] = -1;
        for (int f = 0; f < 6; ++f) {
#ifdef __CUDA_ARCH__
            const int corners[4] = {packed::faceCorner(f, 0), packed::faceCorner(f, 1),
                                    packed::faceCorner(f, 2), packed::faceCorner(f, 3)};
#else
            const int* corners = kFace[f]; // (a copy costs the host 9% more instructions here)
#endif
            int enter[2] = {}, leave[2] = {}, ne = 0, nl = 0;
            for (int k = 0; k < 4; ++k) {
                const int a = corners[k], b = corners[(k + 1) & 3];
                if (inside(c[a]) == inside(c[b])) continue;
                if (inside(c[b]))
                    enter[ne++] = k;
                else
                    leave[nl++] = k;
            }
            if (ne == 0) continue;
            auto edge = [&](int k) { return edgeIndex(corners[k], corners[(k + 1) & 3]); };
            if (ne == 1) {
                next[edge(enter[0])] = edge(leave[0]), face[edge(enter[0])] = f;
                continue;
            }
            ambiguous = true;
            const double v0 = c[corners[0]], v1 = c[corners[1]], v2 = c[corners[2]],
                         v3 = c[corners[3]];
            const double saddle = (v0 * v2 - v1 * v3) / (v0 + v2 - v1 - v3);
            const int step =
                inside(float(saddle)) ? 3 : 1; // inside joined: previous edge; else next
            for (int e = 0; e < 2; ++e)
                next[edge(enter[e])] = edge((enter[e] + step) & 3), face[edge(enter[e])] = f;
        }
    }

    /// Calls polygon(edges, n) for each closed polygon, its crossing edges in order.
    template <typename F> FLUIDSURF_HD constexpr void forEach(F&& polygon) const
    {
        bool done[12] = {};
        for (int start = 0; start < 12; ++start) {
            if (next[start] < 0 || done[start]) continue;
            int edges[12] = {}, n = 0;
            for (int e = start; !done[e]; e = next[e])
                done[e] = true, edges[n++] = e;
            polygon(edges, n);
        }
    }
};

namespace detail {
/// Per sign pattern of a cell's corners (bit n: corner n inside): whether a face has four
/// crossings (its cut then needs the values), and otherwise the cell's polygons, which the
/// signs alone decide. Host only (the device, and a cell with four crossings on a face, still
/// cut it): looked up, with the counting pass' triangles (cellTriangles), the 13.1M drop's mesh
/// stage took 0.256 -> 0.213 s on 2 cores.
struct CellCases
{
    static constexpr int kMaxFan = 4; ///< (a larger fan would fail this table's compilation)
    CellPolygons polygons[256];
    bool fourCrossings[256] = {};
    /// The triangles of the polygons fanned (a polygon of n edges: n - 2).
    int triangles[256] = {};
    /// Those triangles as cell edges, in the order the mesher writes them: polygon by polygon
    /// (forEach's order), each fanned from its first edge.
    signed char fan[256][kMaxFan][3] = {};
    constexpr CellCases() : polygons{}
    {
        for (int pattern = 0; pattern < 256; ++pattern) {
            for (int f = 0; f < 6; ++f) {
                int crossings = 0;
                for (int k = 0; k < 4; ++k)
                    crossings +=
                        (pattern >> kFace[f][k] & 1) != (pattern >> kFace[f][(k + 1) & 3] & 1);
                fourCrossings[pattern] = fourCrossings[pattern] || crossings == 4;
            }
            if (fourCrossings[pattern]) continue;
            polygons[pattern] = CellPolygons(pattern);
            int& fanned = triangles[pattern];
            auto& out = fan[pattern];
            polygons[pattern].forEach([&fanned, &out](const int* edges, int n) {
                for (int k = 1; k + 1 < n; ++k, ++fanned) {
                    out[fanned][0] = static_cast<signed char>(edges[0]);
                    out[fanned][1] = static_cast<signed char>(edges[k]);
                    out[fanned][2] = static_cast<signed char>(edges[k + 1]);
                }
            });
        }
    }
};
inline constexpr CellCases kCellCases{};
} // namespace detail

/// The triangles of a cell whose faces have at most two crossings each (its polygons fanned),
/// from its corners' signs; -1 for a cell with four crossings on a face (cut it: CellPolygons).
/// Host only: the mesher's counting pass needs no more.
inline int cellTriangles(const float c[8])
{
    const int pattern = cellSignPattern(c);
    return detail::kCellCases.fourCrossings[pattern] ? -1 : detail::kCellCases.triangles[pattern];
}

/// A cell whose faces have at most two crossings each: its polygons (the table's), and their
/// triangles as cell edges (fanned as the mesher writes them); null for a cell with four
/// crossings on a face (cut it: CellPolygons). Host only.
struct CellFan
{
    const CellPolygons* polygons = nullptr;
    const signed char (*triangles)[3] = nullptr;
    int count = 0;
};
inline CellFan cellFan(const float c[8])
{
    const int pattern = cellSignPattern(c);
    if (detail::kCellCases.fourCrossings[pattern]) return {};
    return {&detail::kCellCases.polygons[pattern], detail::kCellCases.fan[pattern],
            detail::kCellCases.triangles[pattern]};
}

FLUIDSURF_HD inline CellPolygons::CellPolygons(const float c[8])
{
#ifndef __CUDA_ARCH__
    const int pattern = cellSignPattern(c);
    if (!detail::kCellCases.fourCrossings[pattern]) {
        *this = detail::kCellCases.polygons[pattern];
        return;
    }
#endif
    cut(c);
}

} // namespace mesh
} // namespace fluidsurf
