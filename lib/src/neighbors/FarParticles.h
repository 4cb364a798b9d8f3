// FarParticles.h - particles so far from all others that the cell grid cannot hold them with the
// rest (more than kMaxCellsPerAxis cells along an axis): one stray particle 1e7 r away must not
// fail the frame. Such a particle has no neighbour within h, so it is isolated by definition
// (Classify.h); it is taken out before the grid is built and reported as isolated.
#pragma once

#include <fluidsurf/Vec3.h>

#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace neighbors {

/// Whether the particles' bounding box spans more cells of size cellSize than the grid holds.
bool exceedsCellRange(const std::vector<Vec3f>& positions, double cellSize);

/// Indices of the particles that, along some axis, lie more than gap from every other particle
/// (so no other particle is within gap of them), ascending.
std::vector<uint32_t> axisSingletons(const std::vector<Vec3f>& positions, double gap);

} // namespace neighbors
} // namespace fluidsurf
