// TransferAttributes.h - particle attributes (velocity, density, id, ...) carried onto points of
// the surface: mesh vertices, or anything else near the particles.
//
// Float attributes: a moving-least-squares fit of a linear function over the particles within
// the influence radius R, with the field's kernel w = max(0, (1 - |x - x_j|^2 / R^2))^3 (thesis
// eq. 4.5) as weights, evaluated at the point. It reproduces a linear field exactly: a plain
// weighted average would not, because a surface point lies off the particles' centre of mass
// (by about r, on one side), which biases it by |grad f| * r - a rigid rotation's velocity by
// |omega| r. As weights: value = sum_j w_j (1/W - u . (d_j - dbar)) f_j with d_j = x_j - x,
// W = sum w_j, dbar = sum w_j d_j / W, u = M^-1 dbar and M = sum w_j (d_j - dbar)(d_j - dbar)^T
// (with a ridge of 1e-4 trace(M) on M: where the particles form a sheet or a line, the slope
// across them is unknown and taken as flat). Where the particles within R spread too little
// (det M < 0.01 (trace M / 3)^3: a point of the band's outer layer sees one layer of particles),
// the fit is made over 2R instead when the particles there spread enough. Integer attributes (ids,
// flags) are not averaged: each point takes the nearest particle's. A point with no particle within
// R takes the nearest particle's value, for floats too.
//
// Parallel over points, each summed in the same order for any thread count (deterministic).
#pragma once

#include <fluidsurf/Context.h>
#include <fluidsurf/ParticleSet.h>

#include <openvdb/openvdb.h>

#include <string>
#include <vector>

namespace fluidsurf {

/// The particle attribute a name asks for: the attribute of that exact name, else the one
/// playing the role the name is an alias of ("velocity" finds "v", "rho" finds "Rhop"). nullptr
/// when there is none.
const Attribute* findAttribute(const ParticleSet& particles, const std::string& name);

/// ValueError naming the first of names that findAttribute does not find (listing the particles'
/// attributes), or a name that finds the same attribute as an earlier one.
void checkAttributeNames(const ParticleSet& particles, const std::vector<std::string>& names);

/// The attributes named (see findAttribute; each result keeps the particle attribute's name,
/// type and components) at each point, in the order of names. influenceRadius: R, world units,
/// > 0. ValueError as checkAttributeNames; Cancelled when ctx's callback stops it. Timed as
/// "transfer".
std::vector<Attribute> transferAttributes(const ParticleSet& particles,
                                          const std::vector<std::string>& names,
                                          const std::vector<Vec3f>& points, double influenceRadius,
                                          Context& ctx);

/// The same at the active voxels of levelSet, as VDB grids of its transform and active topology
/// (background 0), named after the attributes, for a .vdb beside the level set (as Houdini's
/// particle surfacer writes "v"): a float 3-vector as a Vec3fGrid, a float scalar as a
/// FloatGrid, an integer as an Int32Grid (Int64Grid where a value needs it); other component counts
/// as one grid per component (name0, name1, ...). Timed as "transfer" too.
openvdb::GridPtrVec attributeGrids(const ParticleSet& particles,
                                   const std::vector<std::string>& names,
                                   const openvdb::FloatGrid& levelSet, double influenceRadius,
                                   Context& ctx);

} // namespace fluidsurf
