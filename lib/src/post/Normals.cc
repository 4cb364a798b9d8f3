// Normals.cc - angle-weighted vertex normals (see Normals.h).
//
// Each vertex gathers from its own triangles (a vertex -> triangle table built by counting, its
// lists in triangle order), rather than each triangle scattering into its vertices: the sums
// need no atomics, and each runs in the same order on every run.
#include "post/Normals.h"

#include "util/Angle.h"
#include "util/Incidence.h"
#include "util/Memory.h"
#include "util/Vec3d.h"

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

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
        // The corners' products a kBatch at a time, their angles at once (util::angles: one
        // atan2 at a time was two thirds of this step), then each vertex's sum in its order.
        constexpr size_t kBatch = 256;
        Vec3d n[kBatch];
        double len[kBatch], dot[kBatch], angle[kBatch];
        size_t of[kBatch], m = 0;
        size_t v = r.begin(); // the vertex being summed
        Vec3d sum(0.0);
        auto finish = [&] { // v's normal; on to the next
            const double l = sum.length();
            mesh.normals[v] = l > 0 ? Vec3f(float(sum[0] / l), float(sum[1] / l), float(sum[2] / l))
                                    : Vec3f(0, 0, 0);
            sum = Vec3d(0.0);
            ++v;
        };
        auto flush = [&] {
            if (m == 0) return;
            util::angles(len, dot, angle, m);
            for (size_t j = 0; j < m; ++j) {
                while (v != of[j])
                    finish();
                if (len[j] == 0) continue; // a degenerate triangle has no direction
                sum += n[j] * (angle[j] / len[j]);
            }
            m = 0;
        };
        for (size_t w = r.begin(); w != r.end(); ++w) {
            const Vec3d p = toVec3d(mesh.points[w]);
            for (uint32_t i = start[w]; i < start[w + 1]; ++i) {
                const auto& t = mesh.triangles[corner[i]];
                const int k = t[0] == w ? 0 : t[1] == w ? 1 : 2;
                const Vec3d a = toVec3d(mesh.points[t[(k + 1) % 3]]) - p,
                            b = toVec3d(mesh.points[t[(k + 2) % 3]]) - p;
                n[m] = a.cross(b);
                len[m] = n[m].length();
                dot[m] = a.dot(b);
                of[m++] = w;
                if (m == kBatch) flush();
            }
        }
        flush();
        while (v != r.end())
            finish();
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
