// Decimate.h - parallel quadric-error decimation (thesis §5.2.1, Garland and Heckbert 1997):
// edge collapses, cheapest first, each to the point of least quadric error (or, where that point
// would leave a sliver or a fold, to the edge's middle or an end), guarded so that a closed
// manifold surface stays closed, manifold, oriented and free of flipped or sliver triangles.
// The same result for any thread count.
#pragma once

#include <fluidsurf/Mesh.h>

#include <cstddef>
#include <limits>
#include <vector>

namespace fluidsurf {
namespace post {

/// Where decimation stops: at whichever of the two comes first.
struct DecimateTarget
{
    /// Collapse until at most this many triangles are left (0: no count target).
    size_t triangles = 0;
    /// Collapse nothing whose error exceeds this (a squared length: the collapsed vertex's
    /// area-weighted mean squared distance to the original triangles' planes it stands for).
    double maxError = std::numeric_limits<double>::infinity();
    /// Collapse nothing that could leave a vertex farther than this from the input surface
    /// (world units): each vertex carries a bound, its ends' larger bound plus the new point's
    /// largest distance to the planes of the triangles the collapse replaces.
    double maxDrift = std::numeric_limits<double>::infinity();
    /// Collapse nothing that moves the surface locally by more than this (world units): the
    /// new point must lie this close to a triangle it replaces, and each old end this close
    /// to a new triangle.
    double maxStep = std::numeric_limits<double>::infinity();
};

struct DecimateStats
{
    size_t passes = 0;    ///< rounds of blocks (see Decimate.cc)
    size_t collapses = 0; ///< edges collapsed, two triangles each
    double maxError = 0;  ///< the largest error of a collapse made (squared length)
    double maxDrift = 0;  ///< the largest drift bound a vertex was given (length)
    size_t refused = 0;   ///< collapses a guard refused
};

/// mesh decimated to target, without normals (see Normals.h). Vertices on an open border, on a
/// non-manifold edge or of a non-manifold fan never move, so whatever was open or non-manifold
/// stays as it was. Points not used by the result are dropped; `kept`, if given, gets each
/// result point's index in mesh (the points a collapse merged keep the index of one end).
/// mesh by value: its triangles become the work's own (move a mesh in to spare the copy).
TriangleMesh decimate(TriangleMesh mesh, const DecimateTarget& target,
                      DecimateStats* stats = nullptr, std::vector<uint32_t>* kept = nullptr);

} // namespace post
} // namespace fluidsurf
