// RayCrossings.h - which mesh component holds each particle, on the GPU (host facade, no CUDA
// syntax): post::componentsOfParticles' ray test (lib/src/post/ParticleVolumes.h) over the rays
// the host has binned (post::rayColumns), each triangle's plane and each crossing from the shared
// math of lib/src/post/RayPlanes.h without FMA contraction, each ray's crossings gathered by
// component in the planes' order: the CPU's answer for every particle.
#pragma once

#include <fluidsurf/Vec3.h>

#include <cstddef>
#include <cstdint>

namespace fluidsurf {
namespace cuda {

struct RayInput
{
    const Vec3f* points = nullptr;
    size_t pointCount = 0;
    const uint32_t* triangles = nullptr; ///< 3 a triangle
    size_t triangleCount = 0;
    const uint32_t* ofPoint = nullptr; ///< each point's component, or UINT32_MAX for none
    const uint8_t* outward = nullptr;  ///< per component: its volume is positive
    size_t componentCount = 0;
    const Vec3f* particles = nullptr;
    size_t particleCount = 0;
    /// the rays (post::RayColumns): along axis, (u, v) across, columns of `cell` from (u0, v0),
    /// nu a row; column c's triangles tris[start[c], start[c + 1]), its particles
    /// sorted[first[c], first[c + 1])
    int axis = 0, u = 1, v = 2;
    double u0 = 0, v0 = 0, cell = 1, nudgeU = 0, nudgeV = 0;
    int64_t nu = 1;
    size_t columnCount = 0;
    const uint32_t *start = nullptr, *tris = nullptr, *first = nullptr, *sorted = nullptr;
};

/// Each particle's component into out (particleCount; UINT32_MAX where none holds it). False,
/// out unspecified, where a ray crossed more components than a device thread keeps (the CPU's
/// answer is then the caller's to find). Throws fluidsurf::Error on CUDA errors.
bool componentsOnDevice(const RayInput& input, uint32_t* out, void* stream = nullptr);

} // namespace cuda
} // namespace fluidsurf
