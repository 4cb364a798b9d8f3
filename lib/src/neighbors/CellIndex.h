// CellIndex.h - the neighbour structure of the field pipeline (thesis §4.2.2, "handlerArray" and
// "startIndices"): particles sorted by the Z-order (Morton) id of their cell, cells of a given
// size, plus the sorted list of occupied cells with the range of particles each holds.
//
// Sparse by design: the thesis' startIndices array is dense over the bounding box, so one stray
// particle far away blows it up. Here only occupied cells are stored (sorted unique Morton keys
// + offsets), found through an open-addressing hash table of the keys (a binary search cost 8%
// of the whole pipeline). Memory stays proportional to the particle count, every traversal goes
// in key order (deterministic; the hash is only a lookup), and Z-order keeps cells that are
// close in space close in memory.
#pragma once

#include "neighbors/CellSlot.h"
#include "util/Memory.h"

#include <fluidsurf/Context.h>
#include <fluidsurf/Vec3.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <vector>

namespace fluidsurf {
namespace neighbors {

/// Cells per axis are limited to 2^21 (21 bits per axis in a 63-bit Morton key).
constexpr uint32_t kMaxCellsPerAxis = 1u << 21;

/// 21 bits -> every third bit of 63.
inline uint64_t spreadBits(uint32_t v)
{
    uint64_t x = v & 0x1fffff;
    x = (x | x << 32) & 0x1f00000000ffffull;
    x = (x | x << 16) & 0x1f0000ff0000ffull;
    x = (x | x << 8) & 0x100f00f00f00f00full;
    x = (x | x << 4) & 0x10c30c30c30c30c3ull;
    x = (x | x << 2) & 0x1249249249249249ull;
    return x;
}

/// x in the lowest bit. Inline, like find(): the neighbour walks of classification and of the
/// field's gather look up tens of millions of cells, and the calls were a tenth of the work.
inline uint64_t mortonKey(uint32_t cx, uint32_t cy, uint32_t cz)
{
    return spreadBits(cx) | spreadBits(cy) << 1 | spreadBits(cz) << 2;
}

/// The hash table's first slot for a key (a table of mask + 1 slots): neighbors/CellSlot.h.
inline size_t slotOfKey(uint64_t key, size_t mask)
{
    return size_t(cellSlot(key, mask));
}

struct CellRange
{
    uint32_t begin = 0, end = 0;
    bool empty() const { return begin == end; }
};

/// The index's arrays, hundreds of MB for 13M particles: first touched by the parallel loops
/// that fill them, not zeroed by one thread first (a fifth of the index's time on 2 cores).
template <typename T> using IndexArray = util::NoInitVector<T>;

struct CellIndex
{
    double cellSize = 0;
    double origin[3] = {0, 0, 0};    ///< world position of the corner of cell (0,0,0)
    uint32_t dims[3] = {0, 0, 0};    ///< cells per axis covering the particles
    IndexArray<uint64_t> keys;       ///< occupied cells, ascending Morton keys
    IndexArray<uint32_t> starts;     ///< keys.size() + 1 offsets into the sorted particle arrays
    IndexArray<Vec3f> positions;     ///< particles in cell order
    IndexArray<float> radii;         ///< per-particle radii in cell order; empty: uniform radius
    IndexArray<uint32_t> order;      ///< cell order -> index in the input
    IndexArray<uint64_t> tableKeys;  ///< hash table: key, or kEmptyKey
    IndexArray<uint32_t> tableCells; ///< hash table: position of the key in keys
    static constexpr uint64_t kEmptyKey = ~uint64_t(0);

    /// (Re)build the hash table from keys.
    void buildLookup();

    size_t size() const { return positions.size(); }
    size_t cellCount() const { return keys.size(); }

    /// Cell coordinate of a world position along an axis, clamped to [-1, dims] so callers can
    /// loop over a range without overflow (-1 and dims are never occupied).
    int64_t cellCoord(double v, int axis) const
    {
        const double c = std::floor((v - origin[axis]) / cellSize);
        if (!(c >= 0)) return -1; // also NaN
        if (c >= double(dims[axis])) return dims[axis];
        return int64_t(c);
    }

    /// Particles of cell (cx, cy, cz); empty when outside or unoccupied.
    CellRange find(int64_t cx, int64_t cy, int64_t cz) const
    {
        if (cx < 0 || cy < 0 || cz < 0 || cx >= dims[0] || cy >= dims[1] || cz >= dims[2])
            return {};
        return findKey(mortonKey(uint32_t(cx), uint32_t(cy), uint32_t(cz)));
    }

    /// Particles of the cell with this Morton key (of a cell inside dims); empty if unoccupied.
    CellRange findKey(uint64_t key) const
    {
        if (tableKeys.empty()) return {};
        const size_t mask = tableKeys.size() - 1;
        for (size_t slot = slotOfKey(key, mask);; slot = (slot + 1) & mask) {
            if (tableKeys[slot] == key)
                return {starts[tableCells[slot]], starts[tableCells[slot] + 1]};
            if (tableKeys[slot] == kEmptyKey) return {};
        }
    }

    /// Calls f(begin, end) for every occupied cell overlapping the world box [lo, hi], in
    /// ascending (z, y, x) cell order (deterministic).
    template <typename F> void forEachCellInBox(const double lo[3], const double hi[3], F&& f) const
    {
        int64_t c0[3], c1[3];
        for (int a = 0; a < 3; ++a) {
            c0[a] = cellCoord(lo[a], a);
            c1[a] = cellCoord(hi[a], a);
        }
        for (int64_t cz = c0[2]; cz <= c1[2]; ++cz)
            for (int64_t cy = c0[1]; cy <= c1[1]; ++cy)
                for (int64_t cx = c0[0]; cx <= c1[0]; ++cx) {
                    const CellRange r = find(cx, cy, cz);
                    if (!r.empty()) f(r.begin, r.end);
                }
    }
};

/// CellIndex::forEachCellInBox for a walk that stays in one neighbourhood for a while, such as a
/// thread's run of cells in index (Morton) order, each looking up the cells its box reaches: the
/// last answer for each cell position modulo 8 per axis is kept, and checked by its key. A 4x4x4
/// Morton block of cells and their reach fit without clashes, so most look-ups are answered from
/// 8 KB here instead of the hash table. One per thread.
class NearbyCells
{
public:
    explicit NearbyCells(const CellIndex& index) : mIndex(index)
    {
        for (Entry& e : mEntries)
            e.key = CellIndex::kEmptyKey;
    }

    /// CellIndex::forEachCellInBox(lo, hi, f) through this cache: the same cells in the same
    /// order, the box clipped to the grid first and each axis' key bits spread once per box
    /// instead of once per cell (classification walks 27 cells or more for each cell).
    template <typename F> void forEachCellInBox(const double lo[3], const double hi[3], F&& f)
    {
        int64_t c0[3], c1[3];
        for (int a = 0; a < 3; ++a) {
            // (cells outside the grid are never occupied)
            c0[a] = std::max<int64_t>(mIndex.cellCoord(lo[a], a), 0);
            c1[a] = std::min<int64_t>(mIndex.cellCoord(hi[a], a), int64_t(mIndex.dims[a]) - 1);
            if (c0[a] > c1[a]) return;
        }
        mSpreadX.clear();
        for (int64_t cx = c0[0]; cx <= c1[0]; ++cx)
            mSpreadX.push_back(spreadBits(uint32_t(cx)));
        for (int64_t cz = c0[2]; cz <= c1[2]; ++cz) {
            const uint64_t kz = spreadBits(uint32_t(cz)) << 2;
            for (int64_t cy = c0[1]; cy <= c1[1]; ++cy) {
                const uint64_t kyz = kz | spreadBits(uint32_t(cy)) << 1;
                for (int64_t cx = c0[0]; cx <= c1[0]; ++cx) {
                    const CellRange r = find(cx, cy, cz, mSpreadX[size_t(cx - c0[0])] | kyz);
                    if (!r.empty()) f(r.begin, r.end);
                }
            }
        }
    }

private:
    /// Cell (cx, cy, cz), inside the grid, whose Morton key is key.
    CellRange find(int64_t cx, int64_t cy, int64_t cz, uint64_t key)
    {
        Entry& e = mEntries[(cx & 7) | (cy & 7) << 3 | (cz & 7) << 6];
        if (e.key != key) e.key = key, e.range = mIndex.findKey(key);
        return e.range;
    }

    struct Entry
    {
        uint64_t key;
        CellRange range;
    };
    const CellIndex& mIndex;
    Entry mEntries[512];
    std::vector<uint64_t> mSpreadX; ///< the x cells' spread bits of the box being walked
};

/// The cell grid covering box: origin (a multiple of cellSize, at the corner of the lowest
/// particle's cell) and cells per axis. ValueError when an axis needs
/// more than kMaxCellsPerAxis cells. Shared by the CPU index and the CUDA pipeline.
void cellGrid(const BBox3f& box, double cellSize, double origin[3], uint32_t dims[3]);

/// Sort n particles into cells of the given size (parallel; ctx.checkpoint() per range). radii
/// may be null (uniform).
/// ValueError when the particles span more than kMaxCellsPerAxis cells along an axis.
CellIndex buildCellIndex(const Vec3f* positions, const float* radii, size_t n, double cellSize,
                         Context& ctx);

/// index restricted to the particles whose keep flag (in cell order) is non-zero, in place (no
/// second index at any time); order and cells stay sorted, so no re-sort is needed.
void keepParticles(CellIndex& index, const std::vector<uint8_t>& keep);

} // namespace neighbors
} // namespace fluidsurf
