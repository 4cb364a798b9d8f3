// Reconstruct.cc - the whole reconstruction: radius choice, then the two halves (rasterize,
// mesh), under one context.
#include <fluidsurf/Error.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/SpacingEstimate.h>
#include <fluidsurf/TransferAttributes.h>

#include "backend/Backend.h"
#include "post/IsolatedSpheres.h"
#include "util/Memory.h"
#include "util/Threads.h"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <limits>
#include <vector>

namespace fluidsurf {

ReconstructParams ReconstructParams::fromRadius(double r)
{
    ReconstructParams p;
    p.radius = r;
    return p;
}

Params ReconstructParams::fieldParams(double r) const
{
    // Every length of the field is given in units of r; the products are the ones the CLI has
    // always formed (--voxel 0.5 -> 0.5 * r), so files stay byte-identical.
    Params p = field;
    p.radius = r;
    p.voxelSize = field.voxelSize * r;
    p.influenceRadius = field.influenceRadius * r;
    p.smoothingLength = field.smoothingLength * r;
    p.bandWidth = field.bandWidth * r;
    p.anisotropyRadius = field.anisotropyRadius * r;
    return p;
}

namespace {

/// Lets go of the grid, its leaves freed one after the other on this thread where it is the last
/// owner. (OpenVDB frees a tree's leaves on all threads; each leaf goes back to the arena of the
/// thread that made it, under that arena's lock, and on 16 threads the 13.1M drop's leaves kept
/// the threads queued on those locks for about 20 ms, an H100 host, perf.)
void releaseGrid(openvdb::FloatGrid::Ptr& grid)
{
    if (grid && grid.use_count() == 1) {
        std::vector<openvdb::FloatTree::LeafNodeType*> leaves;
        leaves.reserve(grid->tree().leafCount());
        grid->tree().stealNodes(leaves);
        for (openvdb::FloatTree::LeafNodeType* leaf : leaves)
            delete leaf;
    }
    grid.reset();
}

/// Isolated particles as icospheres of their radius: the radius attribute's value where the field
/// used it, r otherwise. A sphere is left out where float32 cannot place its vertices within
/// 0.1% of its radius (centres beyond ~8,000 radii from the origin): it would collapse into
/// degenerate triangles. Returns the spheres appended.
size_t appendIsolatedSpheres(TriangleMesh& mesh, const ParticleSet& ps,
                             const std::vector<uint32_t>& isolated, const ReconstructParams& params,
                             double r)
{
    // the field's radii: rasterizeParticles has checked them (one positive value each)
    const Attribute* a = params.field.perParticleRadii ? ps.find(AttributeRole::Radius) : nullptr;
    std::vector<Vec3f> centres;
    std::vector<float> radii;
    for (uint32_t i : isolated) {
        const Vec3f& c = ps.positions[i];
        const float radius = a ? a->floats[i] : float(r);
        const float far = std::max({std::abs(c.x), std::abs(c.y), std::abs(c.z)});
        if (far * std::numeric_limits<float>::epsilon() > 1e-3f * radius) continue;
        centres.push_back(c);
        radii.push_back(radius);
    }
    post::appendSpheres(mesh, centres, radii, post::icosphereLevelFor(params.post.sphereDeviation));
    return centres.size();
}

} // namespace

const char* radiusSourceName(RadiusSource s)
{
    switch (s) {
    case RadiusSource::Given:
        return "given";
    case RadiusSource::Attribute:
        return "attribute";
    case RadiusSource::Estimated:
        return "estimate";
    }
    return "?";
}

namespace {
/// r is the attribute's largest value: one absurd value (a pscale of 1e30 among 0.025s) made
/// every length absurd and the mesh empty. ValueError when the largest passes 1000 times the
/// median, naming the particle.
void requireSaneRadii(const Attribute& a)
{
    if (a.floats.empty()) return;
    std::vector<float> sorted(a.floats);
    const auto middle = sorted.begin() + ptrdiff_t(sorted.size() / 2);
    std::nth_element(sorted.begin(), middle, sorted.end());
    const double median = *middle, limit = 1000 * median;
    if (!(median > 0)) return; // (non-positive radii are refused where they are used)
    for (size_t i = 0; i < a.floats.size(); ++i)
        if (!(a.floats[i] <= limit)) {
            char text[300];
            std::snprintf(text, sizeof(text),
                          "radius attribute '%s' of particle %zu is %g, over 1000 times the "
                          "median %g; fix it, or ignore the attribute and give -r",
                          a.name.c_str(), i, double(a.floats[i]), median);
            throw ValueError(text);
        }
}
} // namespace

RadiusChoice chooseRadius(const ParticleSet& ps, double given, bool useAttribute)
{
    Context ctx;
    return chooseRadius(ps, given, useAttribute, ctx);
}

RadiusChoice chooseRadius(const ParticleSet& ps, double given, bool useAttribute, Context& ctx)
{
    RadiusChoice c;
    if (given > 0) {
        c.radius = given, c.source = RadiusSource::Given, c.detail = "given";
        return c;
    }
    if (useAttribute)
        if (const Attribute* a = ps.find(AttributeRole::Radius)) {
            const float r =
                a->floats.empty() ? 0.f : *std::max_element(a->floats.begin(), a->floats.end());
            requireSaneRadii(*a);
            if (r > 0) {
                c.radius = r, c.source = RadiusSource::Attribute;
                c.detail = "largest value of the attribute '" + a->name + "'";
                return c;
            }
        }
    const SpacingEstimate est = [&] {
        const auto t = ctx.scope("radius estimate");
        return util::withThreads(ctx, [&] { return estimateSpacing(ps, ctx); });
    }();
    if (!(est.radius > 0))
        throw ValueError(
            est.sampled > 0 && est.isolated < est.sampled && est.medianNearest == 0
                ? "cannot estimate the particle radius: most particles lie on top of each other "
                  "(the median distance to the nearest one is 0); give it (-r)"
                : "cannot estimate the particle radius (fewer than two particles, or all "
                  "isolated); give it (-r)");
    c.radius = est.radius, c.source = RadiusSource::Estimated;
    c.detail = est.fromDensity ? "half the spacing the particles' density implies"
                               : "half the median nearest-neighbour distance";
    return c;
}

ReconstructResult reconstruct(const ParticleSet& particles, const ReconstructParams& params,
                              Context& ctx, const std::string& sourceName)
{
    validate(params.post);
    checkAttributeNames(particles, params.attributes); // before the work, not after it
    ReconstructResult res;
    // Device::Auto: the CPU for every stage of a run too small for the GPU to pay
    const backend::AutoDevice autoDevice(ctx, particles.size());
    res.radius = chooseRadius(particles, params.radius, params.field.perParticleRadii, ctx);
    RasterizeResult field =
        rasterizeParticles(particles, params.fieldParams(res.radius.radius), ctx, sourceName);
    if (!autoDevice.why().empty()) field.stats.device += " (" + autoDevice.why() + ")";
    ctx.throwIfCancelled();
    res.levelSet = std::move(field.grid); // the result's own: see keepGrids below
    res.adaptiveGrid = std::move(field.adaptive);
    res.isolatedParticles = std::move(field.isolatedParticles);
    res.field = std::move(field.stats);
    // The field's scratch goes back before the mesher's arrays are made (46 MB resident on the
    // 1.7M-particle frame; see util/Memory.h).
    util::returnFreedMemory();
    if (!res.adaptiveGrid.empty()) {
        res.mesh = meshAdaptiveGrid(res.adaptiveGrid, ctx, &res.adaptiveMesh);
        res.meshing.vertices = res.mesh.points.size(),
        res.meshing.triangles = res.mesh.triangles.size();
    } else {
        // no gradient normals for a mesh that post-processing replaces with its own
        res.mesh = meshLevelSet(*res.levelSet, params.mesh.mesher, ctx, &res.meshing,
                                changesMesh(params.post) ? RawNormals::None : RawNormals::Gradient);
    }
    // The finest level's voxel (the adaptive grid's level 3), for post-processing's bounds.
    const double voxel =
        (res.adaptiveGrid.empty() ? res.levelSet : res.adaptiveGrid.level3)->voxelSize()[0];
    if (!params.keepGrids && res.adaptiveGrid.empty()) releaseGrid(res.levelSet);
    // The mesher's scratch (a topology copy of the band, per-leaf pieces) is freed in 4 KiB
    // blocks that malloc keeps; hand them back before post-processing allocates its own.
    util::returnFreedMemory();
    ctx.throwIfCancelled();
    {
        const auto postScope = ctx.scope("post"); // always there: timing trees keep one shape
        PostProcessParams post = params.post;
        if (!(post.voxelSize > 0)) post.voxelSize = voxel;
        ParticleVolumes volumes;
        volumes.positions = particles.positions.data(), volumes.count = particles.size();
        // the field's radii, as the spheres below take them
        const Attribute* a =
            params.field.perParticleRadii ? particles.find(AttributeRole::Radius) : nullptr;
        volumes.radii = a ? a->floats.data() : nullptr, volumes.radius = res.radius.radius;
        std::vector<uint32_t> isolated = res.isolatedParticles; // (in index order, as a rule)
        if (!std::is_sorted(isolated.begin(), isolated.end()))
            std::sort(isolated.begin(), isolated.end());
        volumes.isolated = isolated.data(), volumes.isolatedCount = isolated.size();
        res.mesh = postProcessMesh(std::move(res.mesh), post, ctx, &res.post, &volumes);
        if (params.post.isolated == IsolatedMode::Spheres && !res.isolatedParticles.empty()) {
            const auto t = ctx.scope("isolated spheres");
            res.isolatedSpheres = appendIsolatedSpheres(res.mesh, particles, res.isolatedParticles,
                                                        params, res.radius.radius);
        }
    }
    // At the final vertices: the attributes are a function of position (TransferAttributes.h),
    // so evaluating them after decimation and subdivision loses nothing to those steps.
    if (!params.attributes.empty())
        res.vertexAttributes =
            transferAttributes(particles, params.attributes, res.mesh.points,
                               params.fieldParams(res.radius.radius).influenceRadius, ctx);
    return res;
}

} // namespace fluidsurf
