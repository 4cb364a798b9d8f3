// FarParticles.cc - stray particles beyond the cell grid's reach.
#include "neighbors/FarParticles.h"

#include "neighbors/CellIndex.h"

#include <fluidsurf/ParticleSet.h>

#include <tbb/parallel_sort.h>

#include <algorithm>
#include <cmath>
#include <numeric>

namespace fluidsurf {
namespace neighbors {

bool exceedsCellRange(const std::vector<Vec3f>& positions, double cellSize)
{
    const BBox3f box = boundsOf(positions.data(), positions.size());
    if (box.empty()) return false;
    for (int a = 0; a < 3; ++a) {
        const double origin = std::floor(double(box.min[a]) / cellSize) * cellSize;
        const double cells = std::floor((double(box.max[a]) - origin) / cellSize) + 1;
        if (!(cells < double(kMaxCellsPerAxis))) return true;
    }
    return false;
}

std::vector<uint32_t> axisSingletons(const std::vector<Vec3f>& positions, double gap)
{
    const size_t n = positions.size();
    std::vector<uint8_t> single(n, 0);
    std::vector<uint32_t> order(n);
    for (int a = 0; a < 3; ++a) {
        std::iota(order.begin(), order.end(), 0u);
        tbb::parallel_sort(order.begin(), order.end(), [&](uint32_t i, uint32_t j) {
            return positions[i][a] < positions[j][a] ||
                   (positions[i][a] == positions[j][a] && i < j);
        });
        for (size_t k = 0; k < n; ++k) {
            const double x = positions[order[k]][a];
            const bool before = k == 0 || x - double(positions[order[k - 1]][a]) > gap;
            const bool after = k + 1 == n || double(positions[order[k + 1]][a]) - x > gap;
            if (before && after) single[order[k]] = 1;
        }
    }
    std::vector<uint32_t> out;
    for (size_t i = 0; i < n; ++i)
        if (single[i]) out.push_back(uint32_t(i));
    return out;
}

} // namespace neighbors
} // namespace fluidsurf
