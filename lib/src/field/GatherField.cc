// GatherField.cc - leaf-wise gather of the field sums.
#include "field/GatherField.h"

#include "field/FieldValue.h"
#include "util/Lanes.h"

#include <openvdb/tree/LeafManager.h>

#include <tbb/parallel_for.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstring>
#include <vector>

namespace fluidsurf {
namespace field {

namespace {

using util::kLanes;
using util::Lanes;
constexpr float kFar = 1e30f;    // padding particle: s^2 = inf -> contributes 0

using LeafT = openvdb::FloatTree::LeafNodeType;

inline Lanes load(const float* p) { return util::loadLanes(p); }

/// Particles near one leaf, in leaf-local coordinates, bucketed by z-slab; and the subset of
/// one voxel row. Reused from leaf to leaf by one task.
struct Scratch
{
    std::vector<float> x, y, z, r;            // gathered, unsorted
    std::vector<int> slab;
    std::vector<float> sx, sy, sz, sr;        // sorted by slab
    std::vector<uint32_t> slabStart;
    std::vector<float> rx, ry, rz, rr;        // one row, by slab, padded with kLanes far particles
    std::vector<uint32_t> rowSlabStart;
};

struct Kernel
{
    const neighbors::CellIndex& particles;
    FieldConstants constants;
    double dx, R;
    int slabReach;  // slabs of width dx within R of a voxel on either side
    bool radii;

    int slabCount() const { return LeafT::DIM + 2 * slabReach; }

    // Gather the particles within R of the leaf's voxel box, relative to the leaf origin.
    void gather(const openvdb::Coord& origin, Scratch& s) const
    {
        const double o[3] = {origin.x() * dx, origin.y() * dx, origin.z() * dx};
        const double extent = (LeafT::DIM - 1) * dx;
        double lo[3], hi[3];
        for (int a = 0; a < 3; ++a) lo[a] = o[a] - R, hi[a] = o[a] + extent + R;
        s.x.clear(), s.y.clear(), s.z.clear(), s.r.clear(), s.slab.clear();
        particles.forEachCellInBox(lo, hi, [&](uint32_t b, uint32_t e) {
            for (uint32_t i = b; i < e; ++i) {
                const Vec3f& p = particles.positions[i];
                const double lx = p.x - o[0], ly = p.y - o[1], lz = p.z - o[2];
                if (!(lx > -R && lx < extent + R && ly > -R && ly < extent + R && lz > -R && lz < extent + R)) continue;
                s.x.push_back(float(lx));
                s.y.push_back(float(ly));
                s.z.push_back(float(lz));
                if (radii) s.r.push_back(particles.radii[i]);
                s.slab.push_back(std::clamp(int(std::floor(lz / dx)) + slabReach, 0, slabCount() - 1));
            }
        });
        // Counting sort by slab (stable: the order stays the cell order, deterministic).
        const int slabs = slabCount();
        s.slabStart.assign(slabs + 1, 0);
        for (int b : s.slab) ++s.slabStart[b + 1];
        for (int b = 0; b < slabs; ++b) s.slabStart[b + 1] += s.slabStart[b];
        const size_t n = s.x.size();
        s.sx.resize(n), s.sy.resize(n), s.sz.resize(n), s.sr.resize(radii ? n : 0);
        std::vector<uint32_t>& next = s.rowSlabStart;  // borrowed as the fill cursor
        next.assign(s.slabStart.begin(), s.slabStart.end());
        for (size_t i = 0; i < n; ++i) {
            const uint32_t at = next[s.slab[i]]++;
            s.sx[at] = s.x[i], s.sy[at] = s.y[i], s.sz[at] = s.z[i];
            if (radii) s.sr[at] = s.r[i];
        }
    }

    // The particles within R of the row's (x, y) line, still by slab.
    void selectRow(float vx, float vy, Scratch& s) const
    {
        const float R2 = float(R * R);
        s.rx.clear(), s.ry.clear(), s.rz.clear(), s.rr.clear();
        const int slabs = slabCount();
        s.rowSlabStart.assign(slabs + 1, 0);
        for (int b = 0; b < slabs; ++b) {
            for (uint32_t i = s.slabStart[b]; i < s.slabStart[b + 1]; ++i) {
                const float ex = s.sx[i] - vx, ey = s.sy[i] - vy;
                if (ex * ex + ey * ey >= R2) continue;
                s.rx.push_back(s.sx[i]), s.ry.push_back(s.sy[i]), s.rz.push_back(s.sz[i]);
                if (radii) s.rr.push_back(s.sr[i]);
            }
            s.rowSlabStart[b + 1] = uint32_t(s.rx.size());
        }
        for (int l = 0; l < kLanes; ++l) {
            s.rx.push_back(kFar), s.ry.push_back(kFar), s.rz.push_back(kFar);
            if (radii) s.rr.push_back(0);
        }
    }

    // Sums over row particles [b, e) for the voxel at local (vx, vy, vz). Lanes past e read
    // particles of later slabs or padding, which lie beyond R and add exactly zero.
    template <bool Ssp07, bool Radii>
    FieldSums sums(const Scratch& s, uint32_t b, uint32_t e, float vx, float vy, float vz) const
    {
        const float invR2 = float(1 / (R * R));
        PartialSums<Lanes> acc;
        const float *X = s.rx.data(), *Y = s.ry.data(), *Z = s.rz.data(), *Rr = s.rr.data();
        for (uint32_t j = b; j < e; j += kLanes) {
            const Lanes ex = load(X + j) - vx, ey = load(Y + j) - vy, ez = load(Z + j) - vz;
            const Lanes s2 = (ex * ex + ey * ey + ez * ez) * invR2;
            addParticle<Ssp07, Radii>(acc, ex, ey, ez, s2, Radii ? load(Rr + j) : Lanes{});
        }
        return toFieldSums(acc);
    }

    size_t leaf(LeafT& leaf, Scratch& s) const
    {
        gather(leaf.origin(), s);
        size_t evaluations = 0;
        const auto& mask = leaf.getValueMask();
        for (int i = 0; i < int(LeafT::DIM); ++i)
            for (int j = 0; j < int(LeafT::DIM); ++j) {
                const int rowOffset = (i << 6) | (j << 3);  // OpenVDB leaf layout: z fastest
                bool any = false;
                for (int k = 0; k < int(LeafT::DIM); ++k) any |= mask.isOn(rowOffset + k);
                if (!any) continue;
                const float vx = float(i * dx), vy = float(j * dx);
                selectRow(vx, vy, s);
                for (int k = 0; k < int(LeafT::DIM); ++k) {
                    if (!mask.isOn(rowOffset + k)) continue;
                    const uint32_t b = s.rowSlabStart[k], e = s.rowSlabStart[k + 2 * slabReach + 1];
                    const float vz = float(k * dx);
                    FieldSums sum;
                    if (constants.ssp07)
                        sum = radii ? sums<true, true>(s, b, e, vx, vy, vz) : sums<true, false>(s, b, e, vx, vy, vz);
                    else
                        sum = radii ? sums<false, true>(s, b, e, vx, vy, vz) : sums<false, false>(s, b, e, vx, vy, vz);
                    leaf.setValueOnly(rowOffset + k, fieldValue(sum, constants));
                    ++evaluations;
                }
            }
        return evaluations;
    }
};

} // namespace

size_t evaluateField(openvdb::FloatTree& tree, const neighbors::CellIndex& particles, const Params& params)
{
    const bool radii = !particles.radii.empty();
    Kernel kernel{particles, FieldConstants::from(params, radii), params.voxelSize, params.influenceRadius,
                  int(std::ceil(params.influenceRadius / params.voxelSize)), radii};
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(tree);
    std::atomic<size_t> evaluations{0};
    tbb::parallel_for(leaves.leafRange(1), [&](const openvdb::tree::LeafManager<openvdb::FloatTree>::LeafRange& range) {
        Scratch scratch;
        size_t n = 0;
        for (auto leaf = range.begin(); leaf; ++leaf) n += kernel.leaf(*leaf, scratch);
        evaluations += n;
    });
    return evaluations;
}

} // namespace field
} // namespace fluidsurf
