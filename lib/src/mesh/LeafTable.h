// LeafTable.h - the leaves of a VDB tree by their origins, for marching cubes' passes, which
// look up a leaf's neighbours many times (MarchingCubes.cc).
#pragma once

#include "util/Memory.h"

#include <openvdb/math/Coord.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include <cstddef>
#include <cstdint>

namespace fluidsurf {
namespace mesh {

/// Each leaf's position in the leaf manager by its origin: an open-addressing table at most half
/// full, filled on all threads (a compare-and-swap claims a slot; the origins are distinct, so
/// an insert never needs to compare them). It stands for OpenVDB's probeConstLeaf and a map from
/// each leaf to its position, which the passes asked for a leaf's neighbours (a tree walk and a
/// hash look-up each); the map was filled on one thread. With it and the edge words no longer
/// zeroed first, the first two passes of the 13.1M drop took 19-20 -> 7 ms on 16 threads.
class LeafTable
{
public:
    /// Leaves: an OpenVDB LeafManager (leafCount(), leaf(i).origin()).
    template <typename Leaves> explicit LeafTable(const Leaves& leaves)
    {
        size_t size = 16;
        while (size < 2 * leaves.leafCount())
            size <<= 1;
        mMask = size - 1;
        mSlots.resize(size);
        util::fillInParallel(mSlots, Slot{0, 0, 0, kEmpty});
        tbb::parallel_for(tbb::blocked_range<size_t>(0, leaves.leafCount(), 1024),
                          [&](const tbb::blocked_range<size_t>& r) {
                              for (size_t i = r.begin(); i != r.end(); ++i) {
                                  const openvdb::Coord o = leaves.leaf(i).origin();
                                  for (size_t h = slotOf(o);; h = (h + 1) & mMask) {
                                      uint32_t empty = kEmpty;
                                      if (__atomic_compare_exchange_n(
                                              &mSlots[h].position, &empty, uint32_t(i), false,
                                              __ATOMIC_RELAXED, __ATOMIC_RELAXED)) {
                                          mSlots[h].x = o.x(), mSlots[h].y = o.y(),
                                          mSlots[h].z = o.z();
                                          break;
                                      }
                                  }
                              }
                          });
    }
    /// The position of the leaf at origin o, or -1 where there is none.
    long find(const openvdb::Coord& o) const
    {
        for (size_t h = slotOf(o);; h = (h + 1) & mMask) {
            const Slot& s = mSlots[h];
            if (s.position == kEmpty) return -1;
            if (s.x == o.x() && s.y == o.y() && s.z == o.z()) return long(s.position);
        }
    }

private:
    static constexpr uint32_t kEmpty = UINT32_MAX;
    struct Slot
    {
        int32_t x, y, z;
        uint32_t position;
    };
    size_t slotOf(const openvdb::Coord& o) const
    {
        const uint64_t k = (uint64_t(uint32_t(o.x()) >> 3) * 0x9E3779B97F4A7C15ull) ^
                           (uint64_t(uint32_t(o.y()) >> 3) * 0xC2B2AE3D27D4EB4Full) ^
                           (uint64_t(uint32_t(o.z()) >> 3) * 0x165667B19E3779F9ull);
        return size_t(k ^ k >> 29) & mMask;
    }

    util::NoInitVector<Slot> mSlots;
    size_t mMask = 0;
};

} // namespace mesh
} // namespace fluidsurf
