// AnisotropicField.cc - the anisotropic SSP07 field (see the header). Per leaf, the kernels whose
// boxes reach its active voxels, leaf-local, in the cell index's order; per 4 x 4 x 4 quarter,
// those that can reach it, and per 2 x 2 x 2 block of the quarter (all eight in one pass over the
// quarter's), those that can reach the block (tests eight kernels a register); then the block's
// eight voxels on the eight lanes of a register, kernel after kernel (AnisotropicSums.h says why
// that order gives the same bits for any superset of kernels, which is what lets the device test
// voxel by voxel).
//
// Why blocks and voxel lanes rather than SSP07's kernel lanes (GatherField.cc): each kernel has its
// own shape, so a voxel's neighbours no longer follow from slabs and columns of one radius, and
// with one voxel's candidates on the lanes, the bits would hang on which candidates were tested
// (a kernel that adds zero still moves the later ones to other lanes).
// addKernel takes 8-float registers here, always inlined into functions compiled for AVX2, so no
// call passes one; GCC still warns at the template, which is compiled for the default target.
#pragma GCC diagnostic ignored "-Wpsabi"

#include "field/AnisotropicField.h"

#include "field/AnisotropicSums.h"
#include "field/FieldValue.h"
#include "field/FieldValueWide.h"
#include "field/GatherField.h"
#include "util/Lanes.h"
#include "util/SetBits.h"

#include <fluidsurf/Error.h>

#include <openvdb/tree/LeafManager.h>

#include <immintrin.h>

#include <tbb/parallel_for.h>

#include <atomic>
#include <cmath>
#include <cstring>
#include <vector>

namespace fluidsurf {
namespace field {

namespace {

using LeafT = openvdb::FloatTree::LeafNodeType;
using util::WideLanes;

/// Kernels, leaf-local, in the cell index's order: structure of arrays, padded to a multiple of 8
/// with kernels no test picks (stretch -1: a negative bound).
struct KernelArrays
{
    static constexpr int kArrays = 11; // cx, cy, cz, a0..a5, r, stretch
    std::vector<float> v[kArrays];
    size_t size = 0;

    float* at(int k) { return v[k].data(); }
    const float* at(int k) const { return v[k].data(); }
    /// room for n kernels and the padding, size 0
    void reserveFor(size_t n)
    {
        for (auto& a : v)
            if (a.size() < n + 16) a.resize(n + 16);
        size = 0;
    }
    void pad()
    {
        for (size_t j = size; j < (size + 7) / 8 * 8; ++j) {
            for (int k = 0; k < kArrays - 1; ++k)
                v[k][j] = 0.f;
            v[kArrays - 1][j] = -1.f;
        }
    }
    size_t paddedSize() const { return (size + 7) / 8 * 8; }
};
enum : int { kCx, kCy, kCz, kA0, kR = kA0 + 6, kStretch };

/// The test of a box of voxels whose points lie within h of b (leaf-local): a voxel x lies within
/// h of b, so with H the root of A', |H (c - x)| >= |H (c - b)| - stretch h, and a kernel that
/// reaches x (|H (c - x)| < R) has d.A'd < (R + stretch h)^2 at b; 1e-3 more against the float
/// rounding of d.A'd. (Whether the test is exact decides no bit: see AnisotropicSums.h.)
struct BoxTest
{
    float bx, by, bz, h, R;
};

/// Kernel j of k passes t.
inline bool passes(const KernelArrays& k, size_t j, const BoxTest& t)
{
    const float ex = k.v[kCx][j] - t.bx, ey = k.v[kCy][j] - t.by, ez = k.v[kCz][j] - t.bz;
    const float* a[6] = {&k.v[kA0][j],     &k.v[kA0 + 1][j], &k.v[kA0 + 2][j],
                         &k.v[kA0 + 3][j], &k.v[kA0 + 4][j], &k.v[kA0 + 5][j]};
    const float q = *a[0] * ex * ex + *a[3] * ey * ey + *a[5] * ez * ez +
                    2.f * (*a[1] * ex * ey + *a[2] * ex * ez + *a[4] * ey * ez);
    const float reachOf = t.R + k.v[kStretch][j] * t.h;
    return q < reachOf * reachOf * 1.001f && k.v[kStretch][j] >= 0.f;
}

/// The kernels of from that pass t, into to (in order), one at a time; or their indices into
/// picked (to null).
uint32_t pickNarrow(const KernelArrays& from, const BoxTest& t, KernelArrays* to, uint32_t* picked)
{
    uint32_t n = 0;
    for (size_t j = 0; j < from.size; ++j) {
        if (!passes(from, j, t)) continue;
        if (to)
            for (int a = 0; a < KernelArrays::kArrays; ++a)
                to->v[a][n] = from.v[a][j];
        else
            picked[n] = uint32_t(j);
        ++n;
    }
    if (to) to->size = n, to->pad();
    return n;
}

/// pickNarrow into `to` eight kernels a register with AVX2: the passing lanes packed to the
/// front by one permute (util::kSetBits) and stored whole. (The blocks' index lists:
/// pickBlocksWide.)
__attribute__((target("avx2"))) void pickWide(const KernelArrays& from, const BoxTest& t,
                                              KernelArrays& to)
{
    uint32_t n = 0;
    for (size_t j = 0; j < from.paddedSize(); j += 8) {
        WideLanes l[KernelArrays::kArrays];
        for (int a = 0; a < KernelArrays::kArrays; ++a)
            std::memcpy(&l[a], &from.v[a][j], sizeof l[a]);
        const WideLanes ex = l[kCx] - t.bx, ey = l[kCy] - t.by, ez = l[kCz] - t.bz;
        const WideLanes* a = &l[kA0];
        const WideLanes q = a[0] * ex * ex + a[3] * ey * ey + a[5] * ez * ez +
                            2.f * (a[1] * ex * ey + a[2] * ex * ez + a[4] * ey * ez);
        const WideLanes reachOf = t.R + l[kStretch] * t.h;
        const auto in = (q < reachOf * reachOf * 1.001f) & (l[kStretch] >= 0.f);
        const unsigned mask = unsigned(_mm256_movemask_ps(__m256(in)));
        __m256i order;
        std::memcpy(&order, util::kSetBits.positions[mask], sizeof order);
        for (int c = 0; c < KernelArrays::kArrays; ++c)
            _mm256_storeu_ps(&to.v[c][n], _mm256_permutevar8x32_ps(__m256(l[c]), order));
        n += util::kSetBits.count[mask];
    }
    to.size = n, to.pad();
}

/// pickWide's block tests for all of a quarter's 2 x 2 x 2 blocks in one pass over the
/// quarter's kernels (from), for the blocks whose bit is set in `blocks`: block b's indices into
/// picked + b * stride, their count into n[b]. q: the quarter's centre (leaf-local); a block's
/// centre lies dx from it along each axis (d = sign * dx), so its d.A'd comes from the quarter's
/// e = c - q: (e - d).A(e - d) = e.Ae - 2 d.(Ae) + d.Ad, a few operations a block where the
/// direct form took twenty (the block tests were a fifth of the stage on 2 cores). Its float
/// rounding differs from the direct form's by parts in 1e6 of terms of the size of the bound, far
/// inside the test's 1e-3: a kernel it leaves out reaches no voxel of the block either, and one it
/// keeps that the direct form would not adds exact zeros (AnisotropicSums.h).
__attribute__((target("avx2"))) void pickBlocksWide(const KernelArrays& from, const float q[3],
                                                    float dx, float h, float R, unsigned blocks,
                                                    uint32_t* picked, size_t stride, uint32_t n[8])
{
    for (int b = 0; b < 8; ++b)
        n[b] = 0;
    const __m256i step = _mm256_setr_epi32(0, 1, 2, 3, 4, 5, 6, 7);
    const float dx2 = dx * dx;
    for (size_t j = 0; j < from.paddedSize(); j += 8) {
        WideLanes l[KernelArrays::kArrays];
        for (int a = 0; a < KernelArrays::kArrays; ++a)
            std::memcpy(&l[a], &from.v[a][j], sizeof l[a]);
        const WideLanes ex = l[kCx] - q[0], ey = l[kCy] - q[1], ez = l[kCz] - q[2];
        const WideLanes* a = &l[kA0];
        const WideLanes gx = a[0] * ex + a[1] * ey + a[2] * ez,
                        gy = a[1] * ex + a[3] * ey + a[4] * ez,
                        gz = a[2] * ex + a[4] * ey + a[5] * ez;
        const WideLanes centre = ex * gx + ey * gy + ez * gz + dx2 * (a[0] + a[3] + a[5]);
        const WideLanes tx = 2.f * dx * gx, ty = 2.f * dx * gy, tz = 2.f * dx * gz;
        const WideLanes cxy = 2.f * dx2 * a[1], cxz = 2.f * dx2 * a[2], cyz = 2.f * dx2 * a[4];
        const WideLanes reachOf = R + l[kStretch] * h;
        const WideLanes bound = reachOf * reachOf * 1.001f;
        const auto valid = l[kStretch] >= 0.f;
        const __m256i index = _mm256_add_epi32(_mm256_set1_epi32(int(j)), step);
        for (int b = 0; b < 8; ++b) {
            if (!(blocks >> b & 1)) continue;
            const bool px = b >> 2 & 1, py = b >> 1 & 1, pz = b & 1;
            const WideLanes lin = (px ? tx : -tx) + (py ? ty : -ty) + (pz ? tz : -tz);
            const WideLanes cross =
                (px == py ? cxy : -cxy) + (px == pz ? cxz : -cxz) + (py == pz ? cyz : -cyz);
            const auto in = (centre - lin + cross < bound) & valid;
            const unsigned mask = unsigned(_mm256_movemask_ps(__m256(in)));
            __m256i order;
            std::memcpy(&order, util::kSetBits.positions[mask], sizeof order);
            _mm256_storeu_si256(reinterpret_cast<__m256i*>(&picked[b * stride + n[b]]),
                                _mm256_permutevar8x32_epi32(index, order));
            n[b] += util::kSetBits.count[mask];
        }
    }
}

/// addKernel's operations on eight floats with AVX2 and FMA.
struct WideOps
{
    __attribute__((target("avx2,fma"))) static WideLanes fma(WideLanes a, WideLanes b, WideLanes c)
    {
        return WideLanes(_mm256_fmadd_ps(__m256(a), __m256(b), __m256(c)));
    }
    __attribute__((target("avx2,fma"))) static WideLanes fnma(WideLanes a, WideLanes b, WideLanes c)
    {
        return WideLanes(_mm256_fnmadd_ps(__m256(a), __m256(b), __m256(c)));
    }
    __attribute__((target("avx2"))) static WideLanes one() { return WideLanes{} + 1.f; }
    __attribute__((target("avx2"))) static WideLanes cut(WideLanes t)
    {
        return t > 1e-6f ? t : WideLanes{};
    }
    /// no early way out: eight voxels of a block rarely all miss a picked kernel
    static bool none(WideLanes) { return false; }
};

/// The sums of a block's eight voxels (lane l at (vx[l], vy[l], vz[l]), leaf-local) over the
/// kernels picked[0, n) of k, in order.
template <bool Radii>
__attribute__((target("avx2,fma"))) void
blockSumsWide(const KernelArrays& k, const uint32_t* picked, uint32_t n, const float* vx,
              const float* vy, const float* vz, float invR2, FieldSums out[8])
{
    WideLanes x, y, z;
    std::memcpy(&x, vx, sizeof x), std::memcpy(&y, vy, sizeof y), std::memcpy(&z, vz, sizeof z);
    const WideLanes scale = WideLanes{} + invR2;
    AnisotropicAccumulator<WideLanes> s;
    for (uint32_t p = 0; p < n; ++p) {
        const uint32_t j = picked[p];
        const WideLanes c[3] = {WideLanes{} + k.v[kCx][j], WideLanes{} + k.v[kCy][j],
                                WideLanes{} + k.v[kCz][j]};
        const WideLanes a[6] = {WideLanes{} + k.v[kA0][j],     WideLanes{} + k.v[kA0 + 1][j],
                                WideLanes{} + k.v[kA0 + 2][j], WideLanes{} + k.v[kA0 + 3][j],
                                WideLanes{} + k.v[kA0 + 4][j], WideLanes{} + k.v[kA0 + 5][j]};
        addKernel<WideOps, Radii>(s, c, a, WideLanes{} + k.v[kR][j], x, y, z, scale);
    }
    for (int l = 0; l < 8; ++l)
        out[l] = toSums(s.w[l], s.d0[l], s.d1[l], s.d2[l], s.r[l], s.g0[l], s.g1[l], s.g2[l],
                        s.m0[l], s.m1[l], s.m2[l], s.m3[l], s.m4[l], s.m5[l]);
}

/// blockSumsWide for one voxel on one float: the same operations.
template <bool Radii>
FieldSums voxelSums(const KernelArrays& k, const uint32_t* picked, uint32_t n, float vx, float vy,
                    float vz, float invR2)
{
    AnisotropicAccumulator<float> s;
    for (uint32_t p = 0; p < n; ++p) {
        const uint32_t j = picked[p];
        const float c[3] = {k.v[kCx][j], k.v[kCy][j], k.v[kCz][j]};
        const float a[6] = {k.v[kA0][j],     k.v[kA0 + 1][j], k.v[kA0 + 2][j],
                            k.v[kA0 + 3][j], k.v[kA0 + 4][j], k.v[kA0 + 5][j]};
        addKernel<ScalarFloatOps, Radii>(s, c, a, k.v[kR][j], vx, vy, vz, invR2);
    }
    return toSums(s.w, s.d0, s.d1, s.d2, s.r, s.g0, s.g1, s.g2, s.m0, s.m1, s.m2, s.m3, s.m4, s.m5);
}

/// The active bits of the 2 x 2 x 2 block at (i, j, k) of a leaf, bit l for voxel (i + (l >> 2 &
/// 1), j + (l >> 1 & 1), k + (l & 1)) (the lanes' order).
unsigned blockBits(const LeafT::NodeMaskType& mask, int i, int j, int k)
{
    unsigned bits = 0;
    for (int l = 0; l < 8; ++l)
        bits |= unsigned(mask.isOn(((i + (l >> 2 & 1)) << 6) | ((j + (l >> 1 & 1)) << 3) |
                                   (k + (l & 1))))
                << l;
    return bits;
}

/// One task's arrays, reused from leaf to leaf.
struct Scratch
{
    explicit Scratch(const neighbors::CellIndex& index) : cells(index) {}
    neighbors::NearbyCells cells;
    KernelArrays leaf, quarter;   ///< the leaf's kernels; those of one 4 x 4 x 4 quarter of it
    std::vector<uint32_t> picked; ///< one block's, indices into quarter
};

struct Gather
{
    const AnisotropicKernels& kernels;
    FieldConstants constants;
    double dx;
    float invR2;
    bool radii, wide;
    bool density; ///< Yt10: the radius slot carries V_j W's factor, and the sums go through it

    /// The kernels whose boxes overlap the box of the leaf's active voxels, leaf-local, in the
    /// cell index's order.
    void gather(const LeafT& leaf, Scratch& s) const
    {
        const neighbors::CellIndex& centres = *kernels.centres;
        const openvdb::Coord o = leaf.origin();
        const double origin[3] = {o.x() * dx, o.y() * dx, o.z() * dx};
        int first[3] = {7, 7, 7}, last[3] = {0, 0, 0};
        for (auto v = leaf.cbeginValueOn(); v; ++v) {
            const openvdb::Coord c = v.getCoord() - o;
            for (int a = 0; a < 3; ++a)
                first[a] = std::min(first[a], c[a]), last[a] = std::max(last[a], c[a]);
        }
        double lo[3], hi[3], cellLo[3], cellHi[3];
        for (int a = 0; a < 3; ++a) {
            lo[a] = origin[a] + first[a] * dx, hi[a] = origin[a] + last[a] * dx;
            cellLo[a] = lo[a] - kernels.reach, cellHi[a] = hi[a] + kernels.reach;
        }
        size_t m = 0;
        s.cells.forEachCellInBox(cellLo, cellHi, [&](uint32_t b, uint32_t e) { m += e - b; });
        KernelArrays& k = s.leaf;
        k.reserveFor(m);
        size_t n = 0;
        s.cells.forEachCellInBox(cellLo, cellHi, [&](uint32_t b, uint32_t e) {
            for (uint32_t j = b; j < e; ++j) {
                const Vec3f& p = centres.positions[j];
                const float* ext = &kernels.extent[3 * size_t(j)];
                bool overlaps = true;
                for (int a = 0; a < 3; ++a)
                    overlaps &= p[a] + ext[a] >= lo[a] && p[a] - ext[a] <= hi[a];
                if (!overlaps) continue;
                k.v[kCx][n] = float(double(p.x) - origin[0]);
                k.v[kCy][n] = float(double(p.y) - origin[1]);
                k.v[kCz][n] = float(double(p.z) - origin[2]);
                for (int c = 0; c < 6; ++c)
                    k.v[kA0 + c][n] = kernels.a[6 * size_t(j) + c];
                k.v[kR][n] = density ? kernels.weight[j] : radii ? centres.radii[j] : 0.f;
                k.v[kStretch][n] = kernels.stretch[j];
                ++n;
            }
        });
        k.size = n;
        k.pad();
    }

    size_t leaf(LeafT& leaf, Scratch& s) const
    {
        const auto& mask = leaf.getValueMask();
        if (mask.isOff()) return 0;
        gather(leaf, s);
        s.quarter.reserveFor(s.leaf.size);
        s.picked.resize(s.leaf.size + 16);
        constexpr int kBatch = 64;
        FieldSums sum[kBatch];
        int at[kBatch], m = 0;
        size_t evaluations = 0;
        auto flush = [&] {
            float value[kBatch];
            if (wide && !density) // (FieldValueWide has SSP07's formula alone)
                fieldValuesWide(sum, m, constants, value);
            else
                for (int q = 0; q < m; ++q)
                    value[q] = fieldValue(sum[q], constants);
            for (int q = 0; q < m; ++q)
                leaf.setValueOnly(at[q], value[q]);
            evaluations += size_t(m);
            m = 0;
        };
        float local[8]; // leaf-local coordinates of voxel indices 0..7
        for (int i = 0; i < 8; ++i)
            local[i] = float(i * dx);
        const float R = float(constants.influenceRadius), root3 = float(std::sqrt(3.0));
        // Quarters (4 x 4 x 4 voxels) first, then their 2 x 2 x 2 blocks: each test reads a
        // shorter list (a block's test against the whole leaf's kernels was half the stage).
        for (int q = 0; q < 8; ++q) {
            const int qi = 4 * (q >> 2 & 1), qj = 4 * (q >> 1 & 1), qk = 4 * (q & 1);
            unsigned blocks[8], any = 0;
            for (int b = 0; b < 8; ++b)
                any |= blocks[b] =
                    blockBits(mask, qi + 2 * (b >> 2 & 1), qj + 2 * (b >> 1 & 1), qk + 2 * (b & 1));
            if (!any) continue;
            const BoxTest quarter{float((qi + 1.5) * dx), float((qj + 1.5) * dx),
                                  float((qk + 1.5) * dx), float(1.5 * dx) * root3, R};
            if (wide)
                pickWide(s.leaf, quarter, s.quarter);
            else
                pickNarrow(s.leaf, quarter, &s.quarter, nullptr);
            const size_t stride = s.quarter.paddedSize() + 8;
            uint32_t count[8];
            if (wide) {
                if (s.picked.size() < 8 * stride) s.picked.resize(8 * stride);
                const float centre[3] = {quarter.bx, quarter.by, quarter.bz};
                unsigned used = 0;
                for (int b = 0; b < 8; ++b)
                    used |= unsigned(blocks[b] != 0) << b;
                pickBlocksWide(s.quarter, centre, float(dx), float(0.5 * dx) * root3, R, used,
                               s.picked.data(), stride, count);
            }
            for (int b = 0; b < 8; ++b) {
                const unsigned bits = blocks[b];
                if (!bits) continue;
                const int i = qi + 2 * (b >> 2 & 1), j = qj + 2 * (b >> 1 & 1),
                          kz = qk + 2 * (b & 1);
                const BoxTest block{float((i + 0.5) * dx), float((j + 0.5) * dx),
                                    float((kz + 0.5) * dx), float(0.5 * dx) * root3, R};
                const uint32_t* picked = s.picked.data() + (wide ? b * stride : 0);
                const uint32_t n =
                    wide ? count[b] : pickNarrow(s.quarter, block, nullptr, s.picked.data());
                float vx[8], vy[8], vz[8];
                for (int l = 0; l < 8; ++l)
                    vx[l] = local[i + (l >> 2 & 1)], vy[l] = local[j + (l >> 1 & 1)],
                    vz[l] = local[kz + (l & 1)];
                FieldSums voxels[8];
                if (wide && radii)
                    blockSumsWide<true>(s.quarter, picked, n, vx, vy, vz, invR2, voxels);
                else if (wide)
                    blockSumsWide<false>(s.quarter, picked, n, vx, vy, vz, invR2, voxels);
                else
                    for (int l = 0; l < 8; ++l)
                        if (bits >> l & 1)
                            voxels[l] = radii ? voxelSums<true>(s.quarter, picked, n, vx[l], vy[l],
                                                                vz[l], invR2)
                                              : voxelSums<false>(s.quarter, picked, n, vx[l], vy[l],
                                                                 vz[l], invR2);
                if (m + 8 > kBatch) flush();
                for (int l = 0; l < 8; ++l)
                    if (bits >> l & 1) {
                        at[m] =
                            ((i + (l >> 2 & 1)) << 6) | ((j + (l >> 1 & 1)) << 3) | (kz + (l & 1));
                        sum[m++] = voxels[l];
                    }
            }
        }
        flush();
        return evaluations;
    }
};

} // namespace

size_t evaluateAnisotropicField(openvdb::FloatTree& tree, const AnisotropicKernels& kernels,
                                const Params& params, const Level& level, Context& ctx)
{
    return detail::evaluateAnisotropicField(tree, kernels, params, level, ctx,
                                            fieldLanes() == util::kWideLanes);
}

size_t detail::evaluateAnisotropicField(openvdb::FloatTree& tree, const AnisotropicKernels& kernels,
                                        const Params& params, const Level& level, Context& ctx,
                                        bool wide)
{
    if (wide && fieldLanes() != util::kWideLanes)
        throw ValueError("evaluateAnisotropicField: the wide sums need a CPU with AVX2 and FMA");
    if (!kernels.centres) throw ValueError("evaluateAnisotropicField: no kernels");
    const bool density = params.field == FieldKind::Yt10;
    if (density && kernels.weight.size() != kernels.centres->size())
        throw ValueError("evaluateAnisotropicField: the yt10 field's kernels have no weights");
    const bool radii = density || !kernels.centres->radii.empty();
    const double R = params.influenceRadius;
    const Gather gather{kernels,         fieldConstants(params, level, radii),
                        level.voxelSize, float(1 / (R * R)),
                        radii,           wide,
                        density};
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(tree);
    std::atomic<size_t> evaluations{0};
    tbb::parallel_for(leaves.leafRange(1),
                      [&](const openvdb::tree::LeafManager<openvdb::FloatTree>::LeafRange& range) {
                          ctx.checkpoint();
                          Scratch scratch(*kernels.centres);
                          size_t n = 0;
                          for (auto leaf = range.begin(); leaf; ++leaf)
                              n += gather.leaf(*leaf, scratch);
                          evaluations += n;
                      });
    return evaluations;
}

} // namespace field
} // namespace fluidsurf
