// Normals.cc - angle-weighted vertex normals (see Normals.h).
//
// Each vertex gathers from its own triangles (a vertex -> triangle table built by counting, its
// lists in triangle order), rather than each triangle scattering into its vertices: the sums
// need no atomics, and each runs in the same order on every run.
#include "post/Normals.h"

#include "util/Incidence.h"
#include "util/Memory.h"
#include "util/Vec3d.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <algorithm>
#include <cmath>

namespace fluidsurf {
namespace post {

VertexTriangles::VertexTriangles(const TriangleMesh& mesh)
    : VertexTriangles(mesh.triangles, mesh.points.size())
{
}

VertexTriangles::VertexTriangles(const std::vector<std::array<uint32_t, 3>>& triangles,
                                 size_t points)
    : VertexTriangles(triangles, 0, uint32_t(points))
{
}

VertexTriangles::VertexTriangles(const std::vector<std::array<uint32_t, 3>>& triangles,
                                 uint32_t first, uint32_t last)
{
    const uint32_t n = last - first;
    util::buildIncidence(
        triangles.size(), n,
        [&](size_t t, auto&& emit) {
            for (uint32_t v : triangles[t])
                if (v - first < n) emit(v - first); // (unsigned: below first wraps past n)
        },
        start, tris);
}

void computeAngleWeightedNormals(TriangleMesh& mesh)
{
    computeAngleWeightedNormals(mesh, VertexTriangles(mesh));
}

void computeAngleWeightedNormals(TriangleMesh& mesh, const VertexTriangles& around)
{
    const size_t nv = mesh.points.size();
    const auto &start = around.start, &corner = around.tris;
    util::resizeInParallel(mesh.normals, nv); // (each written below)
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v) {
            const Vec3d p = toVec3d(mesh.points[v]);
            Vec3d sum(0.0);
            for (uint32_t i = start[v]; i < start[v + 1]; ++i) {
                const auto& t = mesh.triangles[corner[i]];
                const int k = t[0] == v ? 0 : t[1] == v ? 1 : 2;
                const Vec3d a = toVec3d(mesh.points[t[(k + 1) % 3]]) - p,
                            b = toVec3d(mesh.points[t[(k + 2) % 3]]) - p;
                const Vec3d n = a.cross(b);
                const double len = n.length();
                if (len == 0) continue; // a degenerate triangle has no direction
                sum += n * (std::atan2(len, a.dot(b)) / len);
            }
            const double len = sum.length();
            mesh.normals[v] =
                len > 0 ? Vec3f(float(sum[0] / len), float(sum[1] / len), float(sum[2] / len))
                        : Vec3f(0, 0, 0);
        }
    });
}

void AreaNormals::compute(const Vec3d* p)
{
    const auto& tris = mMesh.triangles;
    mCross.resize(tris.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, tris.size()),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t t = r.begin(); t != r.end(); ++t)
                              mCross[t] = sideCross(p, tris[t]);
                      });
    const size_t nv = mMesh.points.size();
    mNormals.resize(nv);
    tbb::parallel_for(tbb::blocked_range<size_t>(0, nv), [&](const tbb::blocked_range<size_t>& r) {
        for (size_t v = r.begin(); v != r.end(); ++v) {
            Vec3d n(0.0);
            for (uint32_t i = mAround.start[v]; i < mAround.start[v + 1]; ++i)
                n += mCross[mAround.tris[i]];
            mNormals[v] = n;
        }
    });
}

} // namespace post
} // namespace fluidsurf
