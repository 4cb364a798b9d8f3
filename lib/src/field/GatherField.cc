// GatherField.cc - leaf-wise gather of the field sums.
#include "field/GatherField.h"

#include "field/FieldValue.h"
#include "field/FieldValueWide.h"
#include "field/GatherLayout.h"
#include "util/Floor.h"
#include "util/Lanes.h"
#include "util/Memory.h"
#include "util/Points4.h"
#include "util/SetBits.h"

#include <fluidsurf/Error.h>

#include <openvdb/tree/LeafManager.h>

#include <immintrin.h>

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
constexpr float kFar = 1e30f;          // padding particle: s^2 = inf -> contributes 0
constexpr int kPad = util::kWideLanes; // far particles after a row: enough for either lanes

using LeafT = openvdb::FloatTree::LeafNodeType;
static_assert(LeafT::DIM == GatherLayout::kLeafDim, "GatherLayout lays out OpenVDB's leaves");

inline Lanes load(const float* p)
{
    return util::loadLanes(p);
}

/// Particles near one leaf, in leaf-local coordinates, sorted by z-slab, then by column (bins in
/// x, then in y); and the subset of one voxel row, by z-slab. Reused from leaf to leaf by one
/// task.
struct Scratch
{
    explicit Scratch(const neighbors::CellIndex& index) : cells(index) {}

    /// The cells' look-ups: a task's leaves come in the tree's order, and neighbouring leaves
    /// reach the same cells (through the hash table, a tenth of the gather's leaf work).
    neighbors::NearbyCells cells;
    std::vector<uint64_t> ranges;         // the box's cells' particles, end << 32 | begin
    util::NoInitVector<float> x, y, z, r; // gathered, in cell order
    util::NoInitVector<uint32_t> key;     //   each one's z-slab * B + x-column
    util::NoInitVector<uint16_t> columnY; //   and y-column
    std::vector<uint32_t> byY, count;     // the gathered in y-column order; a counting sort's
    std::vector<float> sx, sy, sz, sr;    // sorted by (z-slab, x-column, y-column), kPad more
    std::vector<uint32_t> sectionStart;   //   where each z-slab's x-column starts (by key)
    std::vector<float> rx, ry, rz, rr;    // one row, by z-slab, padded with kPad far particles
    std::vector<uint32_t> rowSlabStart;   //   where each z-slab starts
};

/// What a row picks from a leaf's sorted particles (sx, ...): in each slab z of [zlo, zhi), the
/// x-columns [xlo, xhi] (sections z B + xlo to z B + xhi, one run), those within R of the row's
/// line (fx, fy) (ex^2 + ey^2 < R2 in float).
struct RowPick
{
    const uint32_t* sectionStart;
    size_t B;
    int xlo, xhi, zlo, zhi;
    float fx, fy, R2;
};

/// The row's picks, appended in order to (rx, ...); slabStart[z] set for z in [zlo, zhi]; returns
/// how many. Written kPad - 1 past the end (room for it: see gather). Eight at a time with AVX2:
/// the chosen lanes packed to the front of each register by one permute (util::kSetBits), stored
/// whole, and the count moved on by their number. The test is the scalar one, float for float
/// (no FMA: the same choices).
template <bool Radii>
__attribute__((target("avx2"))) uint32_t pickWide(const RowPick& row, Scratch& s)
{
    using util::WideLanes;
    uint32_t n = 0;
    for (int z = row.zlo; z < row.zhi; ++z) {
        s.rowSlabStart[z] = n;
        const uint32_t e = row.sectionStart[size_t(z) * row.B + row.xhi + 1];
        for (uint32_t p = row.sectionStart[size_t(z) * row.B + row.xlo]; p < e;
             p += util::kWideLanes) {
            WideLanes x, y, z8, r{};
            std::memcpy(&x, &s.sx[p], sizeof x), std::memcpy(&y, &s.sy[p], sizeof y);
            std::memcpy(&z8, &s.sz[p], sizeof z8);
            if (Radii) std::memcpy(&r, &s.sr[p], sizeof r);
            const WideLanes ex = x - row.fx, ey = y - row.fy;
            const __m256 in = __m256(ex * ex + ey * ey < row.R2);
            const unsigned left = std::min<uint32_t>(e - p, util::kWideLanes);
            const unsigned mask = unsigned(_mm256_movemask_ps(in)) & ((1u << left) - 1);
            __m256i order;
            std::memcpy(&order, util::kSetBits.positions[mask], sizeof order);
            _mm256_storeu_ps(&s.rx[n], _mm256_permutevar8x32_ps(__m256(x), order));
            _mm256_storeu_ps(&s.ry[n], _mm256_permutevar8x32_ps(__m256(y), order));
            _mm256_storeu_ps(&s.rz[n], _mm256_permutevar8x32_ps(__m256(z8), order));
            if (Radii) _mm256_storeu_ps(&s.rr[n], _mm256_permutevar8x32_ps(__m256(r), order));
            n += util::kSetBits.count[mask];
        }
    }
    s.rowSlabStart[row.zhi] = n;
    return n;
}

/// pickWide one at a time, without branches (which particles are left out is unpredictable).
template <bool Radii> uint32_t pickNarrow(const RowPick& row, Scratch& s)
{
    uint32_t n = 0;
    for (int z = row.zlo; z < row.zhi; ++z) {
        s.rowSlabStart[z] = n;
        const uint32_t e = row.sectionStart[size_t(z) * row.B + row.xhi + 1];
        for (uint32_t p = row.sectionStart[size_t(z) * row.B + row.xlo]; p < e; ++p) {
            const float ex = s.sx[p] - row.fx, ey = s.sy[p] - row.fy;
            s.rx[n] = s.sx[p], s.ry[n] = s.sy[p], s.rz[n] = s.sz[p];
            if (Radii) s.rr[n] = s.sr[p];
            n += ex * ex + ey * ey < row.R2;
        }
    }
    s.rowSlabStart[row.zhi] = n;
    return n;
}

/// a b + c and c - a b, each rounded once (for wideSums).
__attribute__((target("avx2,fma"), always_inline)) inline util::WideLanes
fmaLanes(util::WideLanes a, util::WideLanes b, util::WideLanes c)
{
    return util::WideLanes(_mm256_fmadd_ps(__m256(a), __m256(b), __m256(c)));
}
__attribute__((target("avx2,fma"), always_inline)) inline util::WideLanes
fnmaLanes(util::WideLanes a, util::WideLanes b, util::WideLanes c)
{
    return util::WideLanes(_mm256_fnmadd_ps(__m256(a), __m256(b), __m256(c)));
}

/// The particle sums of one voxel (Kernel::sums) on 8 lanes with AVX2 and FMA, where the CPU has
/// them (fieldLanes()): a sixth less field time than 4 lanes on the 1.7M-particle frame. A
/// function compiled for that target alone and picked at run time: the build runs on any x86-64.
///
/// addParticle's arithmetic with its fused multiply-adds written out: the fusions GCC 12 made of
/// it in this target, where the compiler chose them (the outputs kept their bytes when they
/// were written out). |d|^2 = ez ez + (ex ex + ey ey) and t = 1 - |d|^2 / R^2 one rounding each,
/// every sum of a product one fused step; unfused are |d|^2's first square and the products
/// used more than once (t t, t^2 t, t^2 d). So the values' bits are the source's, and a device
/// can do the same, op for op.
template <bool Ssp07, bool Radii>
__attribute__((target("avx2,fma"))) FieldSums
wideSums(const float* X, const float* Y, const float* Z, const float* Rr, uint32_t b, uint32_t e,
         float vx, float vy, float vz, float invR2)
{
    using util::WideLanes;
    const WideLanes one = WideLanes{} + 1.f, scale = WideLanes{} + invR2;
    PartialSums<WideLanes> a;
    for (uint32_t j = b; j < e; j += util::kWideLanes) {
        WideLanes x, y, z, r{}; // (a lambda to load them would be compiled without AVX)
        std::memcpy(&x, X + j, sizeof x), std::memcpy(&y, Y + j, sizeof y);
        std::memcpy(&z, Z + j, sizeof z);
        if (Radii) std::memcpy(&r, Rr + j, sizeof r);
        const WideLanes ex = x - vx, ey = y - vy, ez = z - vz;
        WideLanes t = fnmaLanes(fmaLanes(ez, ez, fmaLanes(ex, ex, ey * ey)), scale, one);
        t = t > 1e-6f ? t : WideLanes{}; // (addParticle's cut-off)
        const WideLanes t2 = t * t, wt = t2 * t;
        a.w += wt;
        a.d0 = fmaLanes(wt, ex, a.d0), a.d1 = fmaLanes(wt, ey, a.d1), a.d2 = fmaLanes(wt, ez, a.d2);
        if (Radii) a.r = fmaLanes(wt, r, a.r);
        if (Ssp07) {
            const WideLanes gx = t2 * ex, gy = t2 * ey, gz = t2 * ez;
            a.g0 += gx, a.g1 += gy, a.g2 += gz;
            a.m0 = fmaLanes(gx, ex, a.m0), a.m1 = fmaLanes(gx, ey, a.m1),
            a.m2 = fmaLanes(gx, ez, a.m2);
            a.m3 = fmaLanes(gy, ey, a.m3), a.m4 = fmaLanes(gy, ez, a.m4),
            a.m5 = fmaLanes(gz, ez, a.m5);
        }
    }
    return toFieldSumsWide(a);
}

/// The box of a leaf's active voxels (at least one): from its mask's words (word x, bit y 8 + z).
/// (OpenVDB's evalActiveBoundingBox visits the active voxels one by one: up to 512 a leaf, for
/// every leaf of the band.)
openvdb::CoordBBox activeBox(const LeafT& leaf)
{
    const auto& mask = leaf.getValueMask();
    int x0 = 8, x1 = -1;
    uint64_t yz = 0;
    for (int x = 0; x < 8; ++x)
        if (const uint64_t w = mask.template getWord<uint64_t>(x)) {
            x0 = std::min(x0, x), x1 = x;
            yz |= w;
        }
    int y0 = 8, y1 = -1;
    uint32_t z = 0;
    for (int y = 0; y < 8; ++y)
        if (const uint32_t row = uint32_t(yz >> (8 * y)) & 0xffu) {
            y0 = std::min(y0, y), y1 = y;
            z |= row;
        }
    const int z0 = __builtin_ctz(z), z1 = 31 - __builtin_clz(z);
    const openvdb::Coord o = leaf.origin();
    return openvdb::CoordBBox(o + openvdb::Coord(x0, y0, z0), o + openvdb::Coord(x1, y1, z1));
}

/// A leaf's gather box (GatherLayout::box): open, leaf-local, and the leaf's origin in world units.
struct GatherBox
{
    double o[3], lo[3], hi[3];
};

/// Where the gather writes the particles it reads, each at the next place, which moves on past
/// those in the box: room for all of them and 4 more (gatherWide stores 4 at a time).
struct GatherOut
{
    float *x, *y, *z, *r;
    uint32_t* key;     ///< z-slab * binCount + x-column
    uint16_t* columnY; ///< y-column
};

/// Particle i into out at n; returns n, moved on by one where i lies in the box. No branch on
/// that: the cells reach past the box, so whether a particle lies in it cannot be predicted.
template <bool Radii>
inline size_t gatherOne(const neighbors::CellIndex& particles, const GatherLayout& layout,
                        const GatherBox& box, uint32_t i, const GatherOut& out, size_t n)
{
    const Vec3f& p = particles.positions[i];
    const double lx = p.x - box.o[0], ly = p.y - box.o[1], lz = p.z - box.o[2];
    const bool in = (lx > box.lo[0]) & (lx < box.hi[0]) & (ly > box.lo[1]) & (ly < box.hi[1]) &
                    (lz > box.lo[2]) & (lz < box.hi[2]);
    out.x[n] = float(lx), out.y[n] = float(ly), out.z[n] = float(lz);
    if (Radii) out.r[n] = particles.radii[i];
    out.key[n] = uint32_t(layout.slabOf(float(lz)) * layout.binCount() + layout.binOf(lx));
    out.columnY[n] = uint16_t(layout.binOf(ly));
    return n + in;
}

/// floor(v) on four lanes, as 32-bit integers (v well inside their range).
__attribute__((target("avx2"), always_inline)) inline __m128i floorLanes(__m256d v)
{
    return _mm256_cvttpd_epi32(_mm256_round_pd(v, _MM_FROUND_TO_NEG_INF | _MM_FROUND_NO_EXC));
}

__attribute__((target("avx2"), always_inline)) inline __m128i clampLanes(__m128i v, __m128i lo,
                                                                         __m128i hi)
{
    return _mm_min_epi32(_mm_max_epi32(v, lo), hi);
}

/// GatherLayout::binOf on four lanes: floor((local / dx + reach) / binSlabs), clamped.
struct GatherWideAxis
{
    __m256d invDx, reach, invBinSlabs;
    __m128i zero, top;

    __attribute__((target("avx2"), always_inline)) __m128i of(__m256d local) const
    {
        return clampLanes(floorLanes(_mm256_mul_pd(
                              _mm256_add_pd(_mm256_mul_pd(local, invDx), reach), invBinSlabs)),
                          zero, top);
    }
};

/// gatherOne for particles [i, i + 4 k) of [i, e), four at a time in AVX registers where the CPU
/// has AVX2; returns where it stopped, and n moved on. The same double subtractions, tests,
/// products and floors on each lane as gatherOne (no FMA in this target), GatherLayout's slabOf
/// and binOf written out: floor by rounding, clamp in integers. The kept lanes are packed to
/// the front of each register by one permute (util::kSetBits) and stored whole. One at a time,
/// this loop was most of the gather's leaf work (the floors above all: 3 a particle).
template <bool Radii>
__attribute__((target("avx2"))) uint32_t
gatherWide(const neighbors::CellIndex& particles, const GatherLayout& layout, const GatherBox& box,
           uint32_t i, uint32_t e, const GatherOut& out, size_t& n)
{
    __m256d o[3], lo[3], hi[3];
    for (int a = 0; a < 3; ++a)
        o[a] = _mm256_set1_pd(box.o[a]), lo[a] = _mm256_set1_pd(box.lo[a]),
        hi[a] = _mm256_set1_pd(box.hi[a]);
    const __m256d invDx = _mm256_set1_pd(layout.invDx), reach = _mm256_set1_pd(layout.reach),
                  invBinSlabs = _mm256_set1_pd(layout.invBinSlabs);
    const __m128i zero = _mm_setzero_si128(), slabTop = _mm_set1_epi32(layout.slabCount() - 1),
                  binTop = _mm_set1_epi32(layout.binCount() - 1),
                  slabReach = _mm_set1_epi32(layout.reach),
                  bins = _mm_set1_epi32(layout.binCount());
    // (helpers of this target: a lambda here would be compiled without AVX)
    const GatherWideAxis bin{invDx, reach, invBinSlabs, zero, binTop};
    for (; i + 4 <= e; i += 4) {
        __m128 ps[3];
        util::splitPoints4(&particles.positions[i], ps[0], ps[1], ps[2]);
        __m256d l[3];
        __m256d in = _mm256_castsi256_pd(_mm256_set1_epi64x(-1));
        for (int a = 0; a < 3; ++a) {
            l[a] = _mm256_sub_pd(_mm256_cvtps_pd(ps[a]), o[a]);
            in = _mm256_and_pd(in, _mm256_and_pd(_mm256_cmp_pd(l[a], lo[a], _CMP_GT_OQ),
                                                 _mm256_cmp_pd(l[a], hi[a], _CMP_LT_OQ)));
        }
        const __m128 fx = _mm256_cvtpd_ps(l[0]), fy = _mm256_cvtpd_ps(l[1]),
                     fz = _mm256_cvtpd_ps(l[2]);
        // slabOf(float(lz)): floor(local / dx) + reach, clamped
        const __m128i slab = clampLanes(
            _mm_add_epi32(floorLanes(_mm256_mul_pd(_mm256_cvtps_pd(fz), invDx)), slabReach), zero,
            slabTop);
        const __m128i key = _mm_add_epi32(_mm_mullo_epi32(slab, bins), bin.of(l[0]));
        const __m128i columnY = bin.of(l[1]);
        const unsigned mask = unsigned(_mm256_movemask_pd(in));
        __m128i order;
        std::memcpy(&order, util::kSetBits.positions[mask], sizeof order);
        _mm_storeu_ps(&out.x[n], _mm_permutevar_ps(fx, order));
        _mm_storeu_ps(&out.y[n], _mm_permutevar_ps(fy, order));
        _mm_storeu_ps(&out.z[n], _mm_permutevar_ps(fz, order));
        if (Radii)
            _mm_storeu_ps(&out.r[n], _mm_permutevar_ps(_mm_loadu_ps(&particles.radii[i]), order));
        _mm_storeu_si128(reinterpret_cast<__m128i*>(&out.key[n]),
                         _mm_castps_si128(_mm_permutevar_ps(_mm_castsi128_ps(key), order)));
        const __m128i y = _mm_castps_si128(_mm_permutevar_ps(_mm_castsi128_ps(columnY), order));
        _mm_storel_epi64(reinterpret_cast<__m128i*>(&out.columnY[n]), _mm_packus_epi32(y, y));
        n += util::kSetBits.count[mask];
    }
    return i;
}

struct Kernel
{
    const neighbors::CellIndex& particles;
    FieldConstants constants;
    GatherLayout layout;
    bool radii;
    int lanes;       // of the sums: util::kLanes or util::kWideLanes (fieldLanes())
    bool wideGather; // gatherWide (AVX2), or gatherOne alone: the same particles either way
    double dx = layout.dx, R = layout.R;
    int reach = layout.reach, window = layout.window;

    int slabCount() const { return layout.slabCount(); }
    int slabOf(double local) const { return layout.slabOf(local); }
    int binCount() const { return layout.binCount(); }
    int binOf(double local) const { return layout.binOf(local); }

    // Gather the particles within R of the leaf's voxel box, relative to the leaf origin, and
    // sort them by z-slab and column. A row then reads only the columns near its (x, y) line
    // instead of testing every particle of the leaf (that test was most of the field stage in
    // thin bands).
    // Only those in the box of the leaf's active voxels are gathered (GatherLayout::box, which
    // says why nothing left out counts): the leaves the band's completion adds hold 23 active
    // voxels on average, and the gather for the whole leaf was most of their cost.
    void gather(const openvdb::Coord& origin, const openvdb::CoordBBox& active, Scratch& s) const
    {
        const double o[3] = {origin.x() * dx, origin.y() * dx, origin.z() * dx};
        const int first[3] = {active.min().x() - origin.x(), active.min().y() - origin.y(),
                              active.min().z() - origin.z()},
                  last[3] = {active.max().x() - origin.x(), active.max().y() - origin.y(),
                             active.max().z() - origin.z()};
        double lo[3], hi[3], cellLo[3], cellHi[3]; // leaf-local; the cells' box in world units
        layout.box(first, last, lo, hi);
        for (int a = 0; a < 3; ++a)
            cellLo[a] = o[a] + lo[a], cellHi[a] = o[a] + hi[a];
        const int B = binCount();
        s.ranges.clear();
        size_t m = 0;
        s.cells.forEachCellInBox(cellLo, cellHi, [&](uint32_t b, uint32_t e) {
            s.ranges.push_back(uint64_t(e) << 32 | b);
            m += e - b;
        });
        constexpr size_t kRoom = 4; // (gatherWide's stores)
        s.x.resize(m + kRoom), s.y.resize(m + kRoom), s.z.resize(m + kRoom);
        s.r.resize(radii ? m + kRoom : 0);
        s.key.resize(m + kRoom), s.columnY.resize(m + kRoom);
        const GatherBox box{{o[0], o[1], o[2]}, {lo[0], lo[1], lo[2]}, {hi[0], hi[1], hi[2]}};
        const GatherOut out{s.x.data(), s.y.data(),   s.z.data(),
                            s.r.data(), s.key.data(), s.columnY.data()};
        size_t n = 0;
        for (const uint64_t range : s.ranges) {
            uint32_t i = uint32_t(range);
            const uint32_t e = uint32_t(range >> 32);
            if (wideGather)
                i = radii ? gatherWide<true>(particles, layout, box, i, e, out, n)
                          : gatherWide<false>(particles, layout, box, i, e, out, n);
            for (; i < e; ++i)
                n = radii ? gatherOne<true>(particles, layout, box, i, out, n)
                          : gatherOne<false>(particles, layout, box, i, out, n);
        }
        s.x.resize(n), s.y.resize(n), s.z.resize(n), s.r.resize(radii ? n : 0);
        s.key.resize(n), s.columnY.resize(n);
        // Sorted by (z-slab, x-column, y-column), and within that in cell order: two stable
        // counting sorts, by the y-column and then by slab and x-column. A row then reads, for
        // each slab, one run of x-columns, and the particles it picks come out by z-slab without
        // a sort of their own (sorting each row's picks by slab was most of the field stage's
        // selection on thin bands: 3.4 active voxels a row on the 13.1M drop).
        s.count.assign(size_t(B) + 1, 0);
        for (uint16_t c : s.columnY)
            ++s.count[c + 1];
        for (int c = 0; c < B; ++c)
            s.count[c + 1] += s.count[c];
        s.byY.resize(n);
        for (size_t i = 0; i < n; ++i)
            s.byY[s.count[s.columnY[i]]++] = uint32_t(i);
        const size_t sections = size_t(slabCount()) * B;
        s.sectionStart.assign(sections + 1, 0);
        for (uint32_t k : s.key)
            ++s.sectionStart[k + 1];
        for (size_t k = 0; k < sections; ++k)
            s.sectionStart[k + 1] += s.sectionStart[k];
        s.count.assign(s.sectionStart.begin(), s.sectionStart.end() - 1); // fill cursors
        for (std::vector<float>* c : {&s.sx, &s.sy, &s.sz})
            c->resize(n + kPad);
        s.sr.resize(radii ? n + kPad : 0);
        for (const uint32_t i : s.byY) {
            const uint32_t at = s.count[s.key[i]]++;
            s.sx[at] = s.x[i], s.sy[at] = s.y[i], s.sz[at] = s.z[i];
            if (radii) s.sr[at] = s.r[i];
        }
        for (size_t l = n; l < n + kPad; ++l) { // (read past a section's end, never picked)
            s.sx[l] = s.sy[l] = s.sz[l] = kFar;
            if (radii) s.sr[l] = 0;
        }
        s.rx.resize(n + kPad), s.ry.resize(n + kPad), s.rz.resize(n + kPad),
            s.rr.resize(radii ? n + kPad : 0);
        s.rowSlabStart.resize(size_t(slabCount()) + 1);
    }

    // The particles within R of row (i, j)'s (x, y) line, by z-slab, slabs [zlo, zhi) only (the
    // active voxels' windows; rowSlabStart is set there): in each slab, the x-columns within R
    // of the line are one run of the sorted particles, and each of them is tested. In the
    // order of the sort, which is the order of the sums.
    void selectRow(int i, int j, int zlo, int zhi, Scratch& s) const
    {
        const double vx = i * dx;
        const RowPick row{s.sectionStart.data(),
                          size_t(binCount()),
                          binOf(vx - R),
                          binOf(vx + R),
                          zlo,
                          zhi,
                          float(vx),
                          float(j * dx),
                          float(R * R)};
        const uint32_t n = lanes == util::kWideLanes // (fieldLanes(): the CPU has AVX2)
                               ? (radii ? pickWide<true>(row, s) : pickWide<false>(row, s))
                               : (radii ? pickNarrow<true>(row, s) : pickNarrow<false>(row, s));
        for (int l = 0; l < kPad; ++l) {
            s.rx[n + l] = s.ry[n + l] = s.rz[n + l] = kFar;
            if (radii) s.rr[n + l] = 0;
        }
    }

    // Sums over row particles [b, e) for the voxel at local (vx, vy, vz). Lanes past e read
    // particles of later slabs or padding, which lie beyond R and add exactly zero.
    template <bool Ssp07, bool Radii>
    FieldSums sums(const Scratch& s, uint32_t b, uint32_t e, float vx, float vy, float vz) const
    {
        const float invR2 = float(1 / (R * R));
        if (lanes == util::kWideLanes)
            return wideSums<Ssp07, Radii>(s.rx.data(), s.ry.data(), s.rz.data(), s.rr.data(), b, e,
                                          vx, vy, vz, invR2);
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
        const auto& mask = leaf.getValueMask();
        if (mask.isOff()) return 0;
        gather(leaf.origin(), activeBox(leaf), s);
        size_t evaluations = 0;
        // The sums of several rows first, then their values, kBatch voxels at a time: the
        // values' divisions, roots and eigen-solves of different voxels then overlap (four to
        // a register with AVX2), and a row's 3.4 active voxels on average no longer leave a
        // register's lanes empty.
        constexpr int kBatch = 64;
        FieldSums sum[kBatch];
        int at[kBatch], m = 0;
        auto flush = [&] {
            float value[kBatch];
            if (lanes == util::kWideLanes) // (fieldLanes(): the CPU has AVX2)
                fieldValuesWide(sum, m, constants, value);
            else
                for (int q = 0; q < m; ++q)
                    value[q] = fieldValue(sum[q], constants);
            for (int q = 0; q < m; ++q)
                leaf.setValueOnly(at[q], value[q]);
            evaluations += size_t(m);
            m = 0;
        };
        for (int i = 0; i < int(LeafT::DIM); ++i)
            for (int j = 0; j < int(LeafT::DIM); ++j) {
                const int rowOffset = (i << 6) | (j << 3); // OpenVDB leaf layout: z fastest
                // the row's 8 bits of the mask (word i holds x = i: bit 8 y + z)
                const unsigned bits = unsigned(mask.template getWord<uint64_t>(i) >> 8 * j) & 0xffu;
                if (!bits) continue;
                const float vx = float(i * dx), vy = float(j * dx);
                const int kmax = 31 - __builtin_clz(bits);
                selectRow(i, j, __builtin_ctz(bits), kmax + window, s);
                if (m + int(LeafT::DIM) > kBatch) flush();
                for (int k = 0; k < int(LeafT::DIM); ++k) {
                    if (!mask.isOn(rowOffset + k)) continue;
                    const uint32_t b = s.rowSlabStart[k], e = s.rowSlabStart[k + window];
                    const float vz = float(k * dx);
                    at[m] = rowOffset + k;
                    if (constants.ssp07)
                        sum[m++] = radii ? sums<true, true>(s, b, e, vx, vy, vz)
                                         : sums<true, false>(s, b, e, vx, vy, vz);
                    else
                        sum[m++] = radii ? sums<false, true>(s, b, e, vx, vy, vz)
                                         : sums<false, false>(s, b, e, vx, vy, vz);
                }
            }
        flush();
        return evaluations;
    }
};

} // namespace

FieldSums detail::wideVoxelSums(const float* X, const float* Y, const float* Z, const float* R,
                                uint32_t b, uint32_t e, float vx, float vy, float vz, float invR2,
                                bool ssp07)
{
    if (fieldLanes() != util::kWideLanes)
        throw ValueError("wideVoxelSums: 8 lanes need a CPU with AVX2 and FMA");
    if (ssp07)
        return R ? wideSums<true, true>(X, Y, Z, R, b, e, vx, vy, vz, invR2)
                 : wideSums<true, false>(X, Y, Z, R, b, e, vx, vy, vz, invR2);
    return R ? wideSums<false, true>(X, Y, Z, R, b, e, vx, vy, vz, invR2)
             : wideSums<false, false>(X, Y, Z, R, b, e, vx, vy, vz, invR2);
}

int fieldLanes()
{
    static const bool wide = __builtin_cpu_supports("avx2") && __builtin_cpu_supports("fma");
    return wide ? util::kWideLanes : util::kLanes;
}

size_t evaluateField(openvdb::FloatTree& tree, const neighbors::CellIndex& particles,
                     const Params& params, const Level& level, Context& ctx, int lanes)
{
    return detail::evaluateField(tree, particles, params, level, ctx, lanes,
                                 util::doubleRegisterLanes() == 4);
}

size_t detail::evaluateField(openvdb::FloatTree& tree, const neighbors::CellIndex& particles,
                             const Params& params, const Level& level, Context& ctx, int lanes,
                             bool wideGather)
{
    if (lanes != util::kLanes && lanes != util::kWideLanes)
        throw ValueError("evaluateField: lanes must be 4 or 8");
    if (lanes == util::kWideLanes && fieldLanes() != lanes)
        throw ValueError("evaluateField: 8 lanes need a CPU with AVX2 and FMA");
    if (wideGather && util::doubleRegisterLanes() != 4)
        throw ValueError("evaluateField: the wide gather needs a CPU with AVX2");
    const bool radii = !particles.radii.empty();
    Kernel kernel{particles,
                  fieldConstants(params, level, radii),
                  GatherLayout::of(level.voxelSize, params.influenceRadius),
                  radii,
                  lanes,
                  wideGather};
    openvdb::tree::LeafManager<openvdb::FloatTree> leaves(tree);
    std::atomic<size_t> evaluations{0};
    tbb::parallel_for(leaves.leafRange(1),
                      [&](const openvdb::tree::LeafManager<openvdb::FloatTree>::LeafRange& range) {
                          ctx.checkpoint();
                          Scratch scratch(particles);
                          size_t n = 0;
                          for (auto leaf = range.begin(); leaf; ++leaf)
                              n += kernel.leaf(*leaf, scratch);
                          evaluations += n;
                      });
    return evaluations;
}

} // namespace field
} // namespace fluidsurf
