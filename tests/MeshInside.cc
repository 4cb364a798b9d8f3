// MeshInside.cc - ray parity against an x-y bin grid of the triangles (see MeshInside.h).
#include "MeshInside.h"

#include <algorithm>
#include <cmath>

namespace fluidsurf {
namespace test {

std::vector<bool> insideMesh(const TriangleMesh& mesh, const std::vector<Vec3f>& points)
{
    std::vector<bool> inside(points.size(), false);
    if (mesh.triangles.empty()) return inside;
    double lo[2] = {1e300, 1e300}, hi[2] = {-1e300, -1e300};
    for (const Vec3f& p : mesh.points)
        for (int a = 0; a < 2; ++a)
            lo[a] = std::min(lo[a], double(p[a])), hi[a] = std::max(hi[a], double(p[a]));
    // about one triangle per bin along each axis's share
    const int bins = std::max(1, int(std::sqrt(double(mesh.triangles.size())) / 2));
    const double size[2] = {(hi[0] - lo[0]) / bins + 1e-12, (hi[1] - lo[1]) / bins + 1e-12};
    auto bin = [&](double v, int a) { return std::clamp(int((v - lo[a]) / size[a]), 0, bins - 1); };
    std::vector<std::vector<uint32_t>> cells(size_t(bins) * bins);
    for (uint32_t t = 0; t < mesh.triangles.size(); ++t) {
        double tlo[2] = {1e300, 1e300}, thi[2] = {-1e300, -1e300};
        for (uint32_t v : mesh.triangles[t])
            for (int a = 0; a < 2; ++a)
                tlo[a] = std::min(tlo[a], double(mesh.points[v][a])),
                thi[a] = std::max(thi[a], double(mesh.points[v][a]));
        for (int j = bin(tlo[1], 1); j <= bin(thi[1], 1); ++j)
            for (int i = bin(tlo[0], 0); i <= bin(thi[0], 0); ++i)
                cells[size_t(j) * bins + i].push_back(t);
    }
    for (size_t k = 0; k < points.size(); ++k) {
        const double px = points[k].x, py = points[k].y, pz = points[k].z;
        if (px < lo[0] || px > hi[0] || py < lo[1] || py > hi[1]) continue;
        int crossings = 0;
        for (uint32_t t : cells[size_t(bin(py, 1)) * bins + bin(px, 0)]) {
            const auto& [a, b, c] = mesh.triangles[t];
            const Vec3f &A = mesh.points[a], &B = mesh.points[b], &C = mesh.points[c];
            // barycentric in x-y (double): the point within the projected triangle?
            const double d = (double(B.y) - C.y) * (double(A.x) - C.x) +
                             (double(C.x) - B.x) * (double(A.y) - C.y);
            if (d == 0) continue; // seen edge-on from above
            const double u =
                ((double(B.y) - C.y) * (px - C.x) + (double(C.x) - B.x) * (py - C.y)) / d;
            const double v =
                ((double(C.y) - A.y) * (px - C.x) + (double(A.x) - C.x) * (py - C.y)) / d;
            if (u < 0 || v < 0 || u + v > 1) continue;
            const double z = u * A.z + v * B.z + (1 - u - v) * C.z;
            crossings += z > pz;
        }
        inside[k] = crossings % 2 == 1;
    }
    return inside;
}

} // namespace test
} // namespace fluidsurf
