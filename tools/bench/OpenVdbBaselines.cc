// OpenVdbBaselines.cc
#include "OpenVdbBaselines.h"

#include "Bench.h"

#include <openvdb/points/PointConversion.h>
#include <openvdb/points/PointRasterizeSDF.h>
#include <openvdb/tools/LevelSetUtil.h>
#include <openvdb/tools/ParticlesToLevelSet.h>
#include <openvdb/tools/VolumeToMesh.h>

namespace fluidsurf {
namespace bench {

namespace {
/// The particle list interface ParticlesToLevelSet expects.
struct ParticleList
{
    using PosType = openvdb::Vec3R;
    const ParticleSet& ps;
    double radius;
    size_t size() const { return ps.size(); }
    void getPos(size_t i, openvdb::Vec3R& p) const
    {
        p = openvdb::Vec3R(ps.positions[i].x, ps.positions[i].y, ps.positions[i].z);
    }
    void getPosRad(size_t i, openvdb::Vec3R& p, openvdb::Real& r) const
    {
        getPos(i, p);
        r = radius;
    }
};
} // namespace

BaselineResult runParticlesToLevelSet(const ParticleSet& ps, double radius, double voxel)
{
    openvdb::initialize();
    BaselineResult out;
    openvdb::FloatGrid::Ptr grid;
    out.seconds = seconds([&] {
        grid = openvdb::createLevelSet<openvdb::FloatGrid>(voxel, 3.0);
        openvdb::tools::ParticlesToLevelSet<openvdb::FloatGrid> raster(*grid);
        raster.setRmin(0); // our particles are ~1 voxel; the default 1.5 would skip them all
        raster.rasterizeSpheres(ParticleList{ps, radius});
        raster.finalize(true);
    });
    out.activeVoxels = grid->activeVoxelCount();
    return out;
}

BaselineResult runSmoothSpheres(const ParticleSet& ps, double radius, double searchRadius,
                                double voxel)
{
    openvdb::initialize();
    BaselineResult out;
    openvdb::points::PointDataGrid::Ptr points;
    out.setupSeconds = seconds([&] {
        std::vector<openvdb::Vec3f> pos(ps.size());
        for (size_t i = 0; i < ps.size(); ++i)
            pos[i] = openvdb::Vec3f(ps.positions[i].x, ps.positions[i].y, ps.positions[i].z);
        // About 8 points per voxel of the point grid (its voxel size is independent of the SDF's).
        auto xform = openvdb::math::Transform::createLinearTransform(4 * radius);
        points = openvdb::points::createPointDataGrid<openvdb::points::NullCodec,
                                                      openvdb::points::PointDataGrid>(pos, *xform);
    });
    openvdb::FloatGrid::Ptr sdf;
    out.seconds = seconds([&] {
        sdf = openvdb::points::rasterizeSmoothSpheres<openvdb::points::PointDataGrid,
                                                      openvdb::FloatGrid>(
            *points, radius, searchRadius, 3.0,
            openvdb::math::Transform::createLinearTransform(voxel));
    });
    out.activeVoxels = sdf->activeVoxelCount();
    return out;
}

TriangleMesh openvdbAdaptiveMesh(const openvdb::FloatGrid& grid, double adaptivity)
{
    std::vector<openvdb::Vec3s> points;
    std::vector<openvdb::Vec3I> triangles;
    std::vector<openvdb::Vec4I> quads;
    openvdb::tools::volumeToMesh(grid, points, triangles, quads, 0.0, adaptivity);
    TriangleMesh m;
    m.points.reserve(points.size());
    for (const auto& p : points)
        m.points.push_back(Vec3f(p.x(), p.y(), p.z()));
    for (const auto& t : triangles)
        m.triangles.push_back({t.x(), t.y(), t.z()});
    for (const auto& q : quads) {
        m.triangles.push_back({q.x(), q.y(), q.z()});
        m.triangles.push_back({q.x(), q.z(), q.w()});
    }
    return m;
}

} // namespace bench
} // namespace fluidsurf
