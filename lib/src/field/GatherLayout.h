// GatherLayout.h - how the field gather (GatherField.h) lays out a leaf's neighbourhood: z-slabs
// one voxel thick, columns of binSlabs slabs in x and y, the window of slabs a voxel reads, and
// the box of particles a leaf gathers. Plain C++ that nvcc also compiles (FLUIDSURF_HD): the CUDA
// gather (cuda/src/GatherField.cu) makes the CPU's picks in the CPU's order with it, so both add
// the same particles on the same lanes and phi has the same bits.
#pragma once

#include "util/Floor.h"
#include "util/HostDevice.h"

#include <math.h>

namespace fluidsurf {
namespace field {

struct GatherLayout
{
    static constexpr int kLeafDim = 8; // voxels a leaf axis (OpenVDB's leaf)

    double dx = 0, R = 0; ///< voxel size and support radius (world units)
    int reach = 0;        ///< slabs of width dx within R of a voxel on either side
    /// The slabs a voxel reads, from reach below its own: 2 reach + 1, less the top one, whose
    /// particles never count. A voxel lies on its own slab's lower face, so the top slab starts
    /// reach dx >= R above it. With the float roundings (the voxel's z: at most 7 dx 2^-24; the
    /// difference, the squares, their sum and the scale by 1 / R^2: 2^-24 each), s^2 >= 1 -
    /// 14 2^-24 = 1 - 8.3e-7 there for reach >= 2, which the sums count as outside (t <= 1e-6:
    /// exact zeros, so every sum keeps its bits). A ninth fewer lanes at R = 4 dx. With reach 1
    /// (voxels of R or more) that bound does not hold, and the slab stays.
    int window = 0;
    int binSlabs = 0; ///< columns are this many slabs wide in x and y (few columns for large R)
    double invDx = 0, invBinSlabs = 0;

    FLUIDSURF_HD static GatherLayout of(double voxelSize, double influenceRadius)
    {
        GatherLayout g;
        g.dx = voxelSize, g.R = influenceRadius;
        g.reach = int(ceil(influenceRadius / voxelSize));
        g.window = g.reach >= 2 ? 2 * g.reach : 2 * g.reach + 1;
        g.binSlabs = (g.slabCount() + 15) / 16; // at most 16 x 16 columns
        g.invDx = 1 / voxelSize, g.invBinSlabs = 1.0 / g.binSlabs;
        return g;
    }

    /// Slabs per axis: the leaf's voxels and reach more on either side.
    FLUIDSURF_HD int slabCount() const { return kLeafDim + 2 * reach; }
    FLUIDSURF_HD int binCount() const { return (slabCount() + binSlabs - 1) / binSlabs; }
    /// The slab of a leaf-local coordinate (the voxel at local 0 reads from slab 0 up).
    FLUIDSURF_HD int slabOf(double local) const
    {
        return clampInt(int(util::floorOf(local * invDx)) + reach, 0, slabCount() - 1);
    }
    /// The column of a leaf-local coordinate in x or y.
    FLUIDSURF_HD int binOf(double local) const
    {
        return clampInt(int(util::floorOf((local * invDx + reach) * invBinSlabs)), 0,
                        binCount() - 1);
    }

    /// The leaf-local box (lo, hi), open, whose particles a leaf gathers, from its active voxels'
    /// box [first, last] (leaf-local voxel indices). What lies outside changes no sum: within a
    /// half voxel more than R of every active row's line in x or y, no row picks it (the float
    /// test is off by 1e-6 voxel at most); and half a voxel below the lowest active voxel's slab
    /// window or above the highest one's, it lies in no voxel's window, while what a window's
    /// last lanes read past its end lies beyond R either way (padding, or the higher slabs).
    FLUIDSURF_HD void box(const int first[3], const int last[3], double lo[3], double hi[3]) const
    {
        const double extent = (kLeafDim - 1) * dx;
        for (int a = 0; a < 3; ++a) {
            const double below = a < 2 ? R : reach * dx, above = a < 2 ? R : (window - reach) * dx;
            const double l = first[a] * dx - below - 0.5 * dx, h = last[a] * dx + above + 0.5 * dx;
            lo[a] = -R < l ? l : -R;                 // std::max(-R, l)
            hi[a] = h < extent + R ? h : extent + R; // std::min(extent + R, h)
        }
    }

private:
    FLUIDSURF_HD static int clampInt(int v, int lo, int hi)
    {
        return v < lo ? lo : hi < v ? hi : v;
    }
};

} // namespace field
} // namespace fluidsurf
