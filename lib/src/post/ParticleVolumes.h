// ParticleVolumes.h - PostProcessParams::volume = Particles: each closed component of the mesh
// gets the volume of the particles inside it (found once it is smoothed), sum_j (2 r_j)^3 (an SPH
// particle's share of the fluid at rest), as the volume that post-processing's offset brings it
// to (Volumes.h), instead of the volume the raw mesh enclosed; and PostProcessParams::cover: the
// centres found in none (CoverParticles.h). SSP07's surface lies 0.87 r above a flat face's
// centres and its f-correction pulls thin sheets in further, so the raw mesh encloses 80-95% of
// the particles' volume on the real frames.
#pragma once

#include "post/Volumes.h"

#include <fluidsurf/PostProcess.h>

#include <cmath>
#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace post {

/// The rays of componentsOfParticles, for it and for another backend's: the triangles binned by
/// the columns of the plane across the rays that their boxes overlap (CSR; the rays run along
/// `axis`, with (u, v) the next two axes in cyclic order), and the particles sorted by column, in
/// input order within one (those outside every column left out). Each ray starts a hair off its
/// particle across it (nudgeU, nudgeV), so that it meets no edge or corner of the mesh.
struct RayColumns
{
    int axis = 0, u = 1, v = 2;
    double u0 = 0, v0 = 0, cell = 1, nudgeU = 0, nudgeV = 0;
    int64_t nu = 0, nv = 0;
    std::vector<uint32_t> start, tris;   ///< column c's triangles: tris[start[c], start[c + 1])
    std::vector<uint32_t> first, sorted; ///< column c's particles: sorted[first[c], first[c + 1])

    int64_t cellOf(double x, double origin) const
    {
        return int64_t(std::floor((x - origin) / cell));
    }
    /// the corner of column c, from which its rays' (u, v) are taken
    double cornerU(size_t c) const { return u0 + double(int64_t(c) % nu) * cell; }
    double cornerV(size_t c) const { return v0 + double(int64_t(c) / nu) * cell; }
};

/// The rays for mesh and particles (empty where either is); cellSize: the grid's cell, about an
/// edge's length (at most about 4M columns whatever it is).
RayColumns rayColumns(const TriangleMesh& mesh, const ParticleVolumes& particles, double cellSize);

/// Which component of mesh (`ofPoint`: each point's; c.volume's sign: outward or a cavity's)
/// holds each particle: of the outward closed components that a ray from the particle (along the
/// axis most of the surface faces) crosses an odd number of times, the one it crosses first,
/// where the ray's crossings say the particle is in the fluid; else kNoComponent (outside, or in
/// a cavity). cellSize:
/// the (y, z) grid the triangles are binned in (about an edge's length). Parallel; the same
/// answer for any thread count. lanes: doubles a register in the ray tests, 2 or 4 (4 needs
/// AVX2; ValueError otherwise), 0 for the CPU's widest: the same answer for each.
std::vector<uint32_t> componentsOfParticles(const TriangleMesh& mesh,
                                            const std::vector<uint32_t>& ofPoint,
                                            const Components& c, const ParticleVolumes& particles,
                                            double cellSize, int lanes = 0);

/// c.volume of every component that holds a particle (`of`: componentsOfParticles') becomes its
/// particles' volume, sum (2 r_j)^3, added in the particles' order; returns how many components
/// changed.
size_t useParticleVolumes(Components& c, const std::vector<uint32_t>& of,
                          const ParticleVolumes& particles);

/// The centres of the particles that `of` (componentsOfParticles') finds in no component, less
/// particles.isolated (the field's own leaving-out), in the particles' order.
std::vector<Vec3f> centresOutside(const std::vector<uint32_t>& of,
                                  const ParticleVolumes& particles);

} // namespace post
} // namespace fluidsurf
