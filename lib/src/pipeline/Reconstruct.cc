// Reconstruct.cc - the whole reconstruction: radius choice, then the two halves (rasterize,
// mesh), under one context.
#include <fluidsurf/Error.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/SpacingEstimate.h>

#include <algorithm>

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
    return p;
}

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

RadiusChoice chooseRadius(const ParticleSet& ps, double given, bool useAttribute)
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
            if (r > 0) {
                c.radius = r, c.source = RadiusSource::Attribute;
                c.detail = "largest value of the attribute '" + a->name + "'";
                return c;
            }
        }
    const SpacingEstimate est = estimateSpacing(ps);
    if (!(est.radius > 0))
        throw ValueError("cannot estimate the particle radius (fewer than two particles, or all "
                         "isolated); give it (-r)");
    c.radius = est.radius, c.source = RadiusSource::Estimated;
    c.detail = "half the median nearest-neighbour distance";
    return c;
}

ReconstructResult reconstruct(const ParticleSet& particles, const ReconstructParams& params,
                              Context& ctx, const std::string& sourceName)
{
    ReconstructResult res;
    res.radius = chooseRadius(particles, params.radius, params.field.perParticleRadii);
    RasterizeResult field =
        rasterizeParticles(particles, params.fieldParams(res.radius.radius), ctx, sourceName);
    ctx.throwIfCancelled();
    res.levelSet = field.grid;
    res.isolatedParticles = std::move(field.isolatedParticles);
    res.field = std::move(field.stats);
    res.mesh = meshLevelSet(*res.levelSet, params.mesh.mesher, ctx, &res.meshing);
    return res;
}

} // namespace fluidsurf
