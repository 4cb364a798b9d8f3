// VolumeToMesh.cc - OpenVDB's mesher behind our mesh type.
#include "mesh/VolumeToMesh.h"

#include "mesh/Gradient.h"
#include "mesh/MarchingCubes.h"

#include <openvdb/tools/Interpolation.h>
#include <openvdb/tools/VolumeToMesh.h>

#include <tbb/parallel_for.h>

namespace fluidsurf {
namespace mesh {

TriangleMesh openvdbVolumeToMesh(const openvdb::FloatGrid& grid, Context& ctx)
{
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    // active tiles as our mesher takes them (MarchingCubes.h): OpenVDB's own handling of them
    // went past 8 GB on some layouts
    openvdb::FloatTree::Ptr keep;
    const openvdb::FloatTree& tree = leafOnlyTree(grid, keep, ctx);
    if (keep) {
        openvdb::FloatGrid tiled(keep);
        tiled.setTransform(grid.transform().copy());
        tiled.setGridClass(grid.getGridClass());
        openvdb::tools::volumeToMesh(tiled, points, triangles, quads, 0.0, 0.0, true);
    } else {
        openvdb::tools::volumeToMesh(grid, points, triangles, quads, 0.0, 0.0, true);
    }

    TriangleMesh mesh;
    mesh.points.resize(points.size());
    mesh.normals.resize(points.size());
    const openvdb::math::Transform& xform = grid.transform();
    tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 1024),
                      [&](const tbb::blocked_range<size_t>& r) {
                          ctx.checkpoint();
                          FloatAccessor acc(tree);
                          for (size_t i = r.begin(); i != r.end(); ++i) {
                              const openvdb::Vec3s& p = points[i];
                              mesh.points[i] = Vec3f(p.x(), p.y(), p.z());
                              // Gradient at the vertex: trilinear blend of the grid-point gradients
                              // of its cell.
                              const openvdb::Vec3d ip = xform.worldToIndex(openvdb::Vec3d(p));
                              const openvdb::Coord c = openvdb::Coord::floor(ip);
                              const openvdb::Vec3d f = ip - c.asVec3d();
                              openvdb::Vec3d g(0.0);
                              for (int n = 0; n < 8; ++n) {
                                  const int dx = n & 1, dy = n >> 1 & 1, dz = n >> 2 & 1;
                                  const double w = (dx ? f.x() : 1 - f.x()) *
                                                   (dy ? f.y() : 1 - f.y()) *
                                                   (dz ? f.z() : 1 - f.z());
                                  if (w > 0) g += indexGradient(acc, c.offsetBy(dx, dy, dz)) * w;
                              }
                              g = xform.baseMap()->applyIJT(g, ip);
                              if (g.lengthSqr() > 0) g.normalize();
                              mesh.normals[i] = Vec3f(float(g.x()), float(g.y()), float(g.z()));
                          }
                      });
    // OpenVDB winds its polygons clockwise seen from outside: reverse them to our convention.
    mesh.triangles.reserve(triangles.size() + 2 * quads.size());
    for (const openvdb::Vec3I& t : triangles)
        mesh.triangles.push_back({t[0], t[2], t[1]});
    for (const openvdb::Vec4I& q : quads) {
        mesh.triangles.push_back({q[0], q[2], q[1]});
        mesh.triangles.push_back({q[0], q[3], q[2]});
    }
    return mesh;
}

} // namespace mesh
} // namespace fluidsurf
