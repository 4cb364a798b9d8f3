// MeshCheck.cc - mesh validity: edges by sorting, vertex fans by union-find on each vertex's link.
#include <fluidsurf/MeshCheck.h>

#include <algorithm>
#include <cmath>
#include <numeric>
#include <sstream>

namespace fluidsurf {

namespace {

struct UnionFind
{
    std::vector<uint32_t> parent;
    explicit UnionFind(size_t n) : parent(n) { std::iota(parent.begin(), parent.end(), 0u); }
    uint32_t find(uint32_t a)
    {
        while (parent[a] != a)
            a = parent[a] = parent[parent[a]];
        return a;
    }
    void join(uint32_t a, uint32_t b) { parent[find(a)] = find(b); }
};

/// Number of connected pieces of a vertex's link (the opposite edges of its triangles): 1 for a
/// manifold vertex (a fan closing into a disc, or an open fan at a boundary).
size_t linkPieces(const std::vector<std::pair<uint32_t, uint32_t>>& link)
{
    std::vector<uint32_t> ids;
    for (const auto& e : link)
        ids.push_back(e.first), ids.push_back(e.second);
    std::sort(ids.begin(), ids.end());
    ids.erase(std::unique(ids.begin(), ids.end()), ids.end());
    UnionFind uf(ids.size());
    auto local = [&](uint32_t v) {
        return uint32_t(std::lower_bound(ids.begin(), ids.end(), v) - ids.begin());
    };
    for (const auto& e : link)
        uf.join(local(e.first), local(e.second));
    size_t pieces = 0;
    for (uint32_t i = 0; i < ids.size(); ++i)
        pieces += uf.find(i) == i;
    return pieces;
}

} // namespace

MeshReport checkMesh(const TriangleMesh& mesh)
{
    MeshReport r;
    const size_t nv = mesh.points.size();
    r.vertices = nv, r.triangles = mesh.triangles.size();

    // Edges: (low, high) key and whether the triangle walks it low -> high.
    std::vector<std::pair<uint64_t, bool>> edges;
    edges.reserve(3 * r.triangles);
    std::vector<uint32_t> degree(nv + 1, 0);
    UnionFind parts(nv);
    for (const auto& t : mesh.triangles) {
        const bool valid = t[0] < nv && t[1] < nv && t[2] < nv;
        if (!valid || t[0] == t[1] || t[1] == t[2] || t[0] == t[2]) {
            ++r.degenerateTriangles;
            if (!valid) continue;
        }
        const Vec3f &a = mesh.points[t[0]], &b = mesh.points[t[1]], &c = mesh.points[t[2]];
        const double ux = double(b.x) - a.x, uy = double(b.y) - a.y, uz = double(b.z) - a.z;
        const double vx = double(c.x) - a.x, vy = double(c.y) - a.y, vz = double(c.z) - a.z;
        const double cx = uy * vz - uz * vy, cy = uz * vx - ux * vz, cz = ux * vy - uy * vx;
        const double twiceArea = std::sqrt(cx * cx + cy * cy + cz * cz);
        const double wx = double(c.x) - b.x, wy = double(c.y) - b.y, wz = double(c.z) - b.z;
        const double longest = std::max({ux * ux + uy * uy + uz * uz, vx * vx + vy * vy + vz * vz,
                                         wx * wx + wy * wy + wz * wz});
        const bool distinct = t[0] != t[1] && t[1] != t[2] && t[0] != t[2];
        if (!(twiceArea > 1e-10 * longest) && distinct)
            ++r.degenerateTriangles;
        else if (distinct) {
            // the smallest angle faces the shortest side: its sine is twice the area over the
            // product of the two sides that meet there
            const double ab = std::sqrt(ux * ux + uy * uy + uz * uz),
                         ac = std::sqrt(vx * vx + vy * vy + vz * vz),
                         bc = std::sqrt(wx * wx + wy * wy + wz * wz);
            const double around = ab <= ac && ab <= bc ? ac * bc : ac <= bc ? ab * bc : ab * ac;
            const double angle = std::asin(std::min(1.0, twiceArea / around)) * 180 / M_PI;
            if (angle < kThinAngleDegrees) ++r.thinTriangles;
            if (r.minAngleDegrees == 0 || angle < r.minAngleDegrees) r.minAngleDegrees = angle;
        }
        r.area += 0.5 * twiceArea;
        r.volume += (double(a.x) * cx + double(a.y) * cy + double(a.z) * cz) / 6; // a . (u x v) / 6
        for (int k = 0; k < 3; ++k) {
            const uint32_t p = t[k], q = t[(k + 1) % 3];
            edges.push_back({uint64_t(std::min(p, q)) << 32 | std::max(p, q), p < q});
            ++degree[p];
        }
        parts.join(t[0], t[1]), parts.join(t[1], t[2]);
    }
    std::sort(edges.begin(), edges.end());
    for (size_t i = 0; i < edges.size();) {
        size_t j = i;
        while (j < edges.size() && edges[j].first == edges[i].first)
            ++j;
        const size_t count = j - i;
        if (count == 1)
            ++r.boundaryEdges;
        else if (count > 2)
            ++r.nonManifoldEdges;
        else if (edges[i].second == edges[i + 1].second)
            ++r.misorientedEdges;
        i = j;
    }

    // Vertex fans, through a vertex -> triangles table.
    std::vector<uint32_t> start(nv + 1, 0);
    for (size_t v = 0; v < nv; ++v)
        start[v + 1] = start[v] + degree[v];
    std::vector<uint32_t> incident(start[nv]), fill(start.begin(), start.end() - 1);
    for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
        const auto& tri = mesh.triangles[t];
        if (tri[0] >= nv || tri[1] >= nv || tri[2] >= nv) continue;
        for (uint32_t v : tri)
            incident[fill[v]++] = t;
    }
    std::vector<std::pair<uint32_t, uint32_t>> link;
    for (size_t v = 0; v < nv; ++v) {
        if (start[v] == start[v + 1]) {
            ++r.unusedVertices;
            continue;
        }
        link.clear();
        for (uint32_t k = start[v]; k < start[v + 1]; ++k) {
            const auto& tri = mesh.triangles[incident[k]];
            const int at = tri[0] == v ? 0 : tri[1] == v ? 1 : 2;
            link.push_back({tri[(at + 1) % 3], tri[(at + 2) % 3]});
        }
        if (linkPieces(link) > 1) ++r.nonManifoldVertices;
        if (parts.find(uint32_t(v)) == v) ++r.components;
    }
    return r;
}

std::string describe(const MeshReport& r)
{
    std::ostringstream s;
    s << r.vertices << " vertices, " << r.triangles << " triangles, " << r.components
      << " component" << (r.components == 1 ? "" : "s") << ", volume " << r.volume << ", area "
      << r.area << ", ";
    if (r.watertight())
        s << "watertight";
    else
        s << "NOT watertight: " << r.boundaryEdges << " boundary edges, " << r.nonManifoldEdges
          << " non-manifold edges, " << r.nonManifoldVertices << " non-manifold vertices, "
          << r.misorientedEdges << " misoriented edges, " << r.degenerateTriangles
          << " degenerate triangles";
    if (r.unusedVertices) s << ", " << r.unusedVertices << " unused vertices";
    s << "; " << r.thinTriangles << " under " << kThinAngleDegrees << " deg (smallest "
      << r.minAngleDegrees << ")";
    return s.str();
}

} // namespace fluidsurf
