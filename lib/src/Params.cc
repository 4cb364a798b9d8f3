// Params.cc - defaults and validation of the pipeline parameters.
#include <fluidsurf/Error.h>
#include <fluidsurf/Params.h>
#include <fluidsurf/Vec3.h>

#include <openvdb/Exceptions.h>

#include <cmath>
#include <cstdio>
#include <utility>

namespace fluidsurf {

Params Params::fromRadius(double r)
{
    Params p;
    p.radius = r;
    p.voxelSize = r;
    p.influenceRadius = 4 * r;
    p.smoothingLength = 4 * r;
    p.bandWidth = 2 * r;
    p.anisotropyRadius = 8 * r;
    return p;
}

namespace {
void requirePositive(double v, const char* name)
{
    if (!(v > 0) || !std::isfinite(v))
        throw ValueError(std::string(name) + " must be a positive finite number (got " +
                         std::to_string(v) + ")");
}
} // namespace

void Params::validate() const
{
    requirePositive(radius, "particle radius");
    requirePositive(voxelSize, "voxel size");
    // (a voxel of 1e38 gave a grid of -inf; see kMaxCoordinate)
    for (const auto& [length, name] : {std::pair<double, const char*>{radius, "particle radius"},
                                       {voxelSize, "voxel size"},
                                       {influenceRadius, "influence radius R"},
                                       {smoothingLength, "smoothing length h"},
                                       {bandWidth, "band width"}})
        if (length > kMaxCoordinate) {
            char text[200];
            std::snprintf(text, sizeof(text),
                          "%s %g is beyond %g world units, where float32 distances overflow; "
                          "scale the positions down",
                          name, length, kMaxCoordinate);
            throw ValueError(text);
        }
    // OpenVDB refuses a transform whose scale determinant is within its tolerance of zero
    // (voxels below about 1.2e-5 world units): say so before any work, in our words.
    try {
        (void)level().transform();
    } catch (const openvdb::Exception&) {
        char text[160];
        std::snprintf(text, sizeof(text),
                      "voxel size %g is too small for an OpenVDB grid (it needs about 2e-5 world "
                      "units or more); scale the particle positions up (e.g. to millimetres)",
                      voxelSize);
        throw ValueError(text);
    }
    requirePositive(influenceRadius, "influence radius R");
    requirePositive(smoothingLength, "smoothing length h");
    requirePositive(bandWidth, "band width");
    requirePositive(halfWidth, "half width");
    if (!std::isfinite(tLow) || !std::isfinite(tHigh) || !(tLow < tHigh))
        throw ValueError("t_low must be smaller than t_high (got " + std::to_string(tLow) + ", " +
                         std::to_string(tHigh) + ")");
    if (!(radiusScale >= 0.5 && radiusScale <= 2))
        throw ValueError("radius scale must be in [0.5, 2] (got " + std::to_string(radiusScale) +
                         ")");
    if (surfaceNeighbours < 0 || splashNeighbours < 0)
        throw ValueError("neighbour thresholds must not be negative");
    if (!std::isfinite(colorFieldThreshold) || colorFieldThreshold < 0)
        throw ValueError("color-field threshold must be a finite number >= 0");
    if (!std::isfinite(colorGradientThreshold) || colorGradientThreshold < 0)
        throw ValueError("color-gradient threshold must be a finite number >= 0");
    if (adaptive && method != FieldMethod::NarrowBand)
        throw ValueError("the adaptive grid runs with the narrow-band method only");
    if (isAnisotropic(field)) {
        if (method != FieldMethod::NarrowBand || adaptive)
            throw ValueError(std::string("the ") + fieldName(field) +
                             " field runs with the narrow-band method on the uniform grid only");
        if (field == FieldKind::Yt10 && !(isoLevel > 0 && isoLevel < 1))
            throw ValueError("iso level must be in (0, 1) (got " + std::to_string(isoLevel) + ")");
        if (!(anisotropyRatio >= 1 && anisotropyRatio <= 8))
            throw ValueError("anisotropy ratio must be in [1, 8] (got " +
                             std::to_string(anisotropyRatio) + ")");
        requirePositive(anisotropyRadius, "anisotropy radius");
        if (anisotropyNeighbours < 0 || anisotropyNeighbours > 10000)
            throw ValueError("anisotropy neighbours must be in [0, 10000]");
        if (!(centreSmoothing >= 0 && centreSmoothing <= 1))
            throw ValueError("centre smoothing must be in [0, 1] (got " +
                             std::to_string(centreSmoothing) + ")");
    }
    if (!std::isfinite(curvatureThreshold) || curvatureThreshold < 0)
        throw ValueError("curvature threshold must be a finite number >= 0 (got " +
                         std::to_string(curvatureThreshold) + ")");
    if (!std::isfinite(levelTolerance) || levelTolerance < 0)
        throw ValueError("level tolerance must be a finite number >= 0 (got " +
                         std::to_string(levelTolerance) + ")");
    // The field kernel reads particles up to R from a vertex; a voxel many times smaller than
    // the particles only multiplies work and memory without adding detail.
    if (voxelSize < radius / 64)
        throw ValueError("voxel size below r/64 is not supported (got " +
                         std::to_string(voxelSize / radius) + " r)");
    // Lengths in voxels index loops and stencils (int32 index space, per-voxel neighbour
    // searches): past 1000 voxels the work explodes long before anything overflows, so each
    // length is bounded there, and the message gives the range.
    const std::pair<double, const char*> lengths[] = {{influenceRadius, "influence radius R"},
                                                      {smoothingLength, "smoothing length h"},
                                                      {bandWidth, "band width"},
                                                      {halfWidth * voxelSize, "half width"},
                                                      {anisotropyRadius, "anisotropy radius"}};
    for (const auto& [length, name] : lengths)
        if (length > 1000 * voxelSize)
            throw ValueError(std::string(name) + " above 1000 voxels is not supported (got " +
                             std::to_string(length / voxelSize) +
                             " voxels; the range is (0, 1000] voxels of " +
                             std::to_string(voxelSize) + ")");
}

const char* fieldName(FieldKind f)
{
    switch (f) {
    case FieldKind::Ssp07:
        return "ssp07";
    case FieldKind::Zb05:
        return "zb05";
    case FieldKind::Ssp07Aniso:
        return "ssp07-aniso";
    case FieldKind::Yt10:
        return "yt10";
    }
    return "?";
}

const char* methodName(FieldMethod m)
{
    switch (m) {
    case FieldMethod::NarrowBand:
        return "narrow-band";
    case FieldMethod::GatherFull:
        return "gather-full";
    case FieldMethod::Scatter:
        return "scatter";
    }
    return "?";
}

FieldKind fieldFromName(const std::string& name)
{
    if (name == "ssp07") return FieldKind::Ssp07;
    if (name == "zb05") return FieldKind::Zb05;
    if (name == "ssp07-aniso") return FieldKind::Ssp07Aniso;
    if (name == "yt10") return FieldKind::Yt10;
    throw ValueError("unknown field '" + name + "' (ssp07, zb05, ssp07-aniso, yt10)");
}

FieldMethod methodFromName(const std::string& name)
{
    if (name == "narrow-band") return FieldMethod::NarrowBand;
    if (name == "gather-full") return FieldMethod::GatherFull;
    if (name == "scatter") return FieldMethod::Scatter;
    throw ValueError("unknown method '" + name + "' (narrow-band, gather-full, scatter)");
}

} // namespace fluidsurf
