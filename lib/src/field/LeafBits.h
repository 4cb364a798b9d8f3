// LeafBits.h - a FloatTree leaf's voxels as 8 words of 64 bits (util/LeafWords.h: word x, bit
// y * 8 + z), for the band completion's frontier scan (CompleteBand.cc): which voxels can find
// anything, and which edges have all the corners of their 4 cells active, decided a leaf at a
// time with word operations instead of probing the 6 neighbours of every voxel of the band.
#pragma once

#include <openvdb/openvdb.h>
#include <openvdb/tree/ValueAccessor.h>

#include <array>
#include <cstdint>

namespace fluidsurf {
namespace field {

using FloatLeaf = openvdb::FloatTree::LeafNodeType;
using Words = std::array<uint64_t, 8>; ///< a leaf's voxels as bits: word x, bit y * 8 + z

/// A leaf's active voxels and the shell of voxels around it, read from its 26 neighbours (their
/// faces, edges and corners; an active tile counts as active voxels): bit z + 1 of
/// rows[x + 1][y + 1], for x, y and z in [-1, 8].
struct ActiveShell
{
    uint16_t rows[10][10] = {};
};
ActiveShell activeShell(const FloatLeaf& home,
                        openvdb::tree::ValueAccessor<const openvdb::FloatTree>& acc);

/// What the frontier scan can pass over, per axis, from a leaf's active shell:
/// - full: the voxels whose edge to the next voxel along the axis has all 18 corners of its 4
///   cells active: a sign change there needs nothing added (a surface crosses millions of such
///   edges);
/// - fullBelow: the same for the edge from the voxel before;
/// - activeBelow: the voxels whose one before is active.
/// Neighbour leaves count: within the leaf alone, 97% of the 13.1M drop's 1.35M crossing edges
/// left for probing, 18 probes each, touched its faces and were full all the same.
struct EdgeStencils
{
    std::array<Words, 3> full, fullBelow, activeBelow;
};
EdgeStencils edgeStencils(const ActiveShell& shell);

/// Per direction (2 axis + (step > 0)), the active voxels of `home` whose frontier scan can find
/// anything in that direction: an inactive neighbour there and |phi| < threshold, or an active
/// neighbour of the other sign. The rest, most of the band, are passed over without a probe (the
/// scan of every voxel's 6 neighbours took 0.64 s of the stage's 0.78 s on the 1.7M-particle
/// t0.50 frame). Neighbours in the 6 adjacent leaves come from their faces (through acc, on
/// the tree that holds home); where one is an active tile, every active voxel is kept.
using Directions = std::array<Words, 6>;
Directions frontierCandidates(const FloatLeaf& home, float threshold,
                              openvdb::tree::ValueAccessor<const openvdb::FloatTree>& acc);

} // namespace field
} // namespace fluidsurf
