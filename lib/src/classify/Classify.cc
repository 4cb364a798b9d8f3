// Classify.cc - neighbour counts and color field per particle, cell by cell.
// The cell loop's templates take and return AVX registers in its AVX2 instance (wideCells).
// They are always inlined there, so no call passes one; GCC still warns at the templates, which
// are compiled for the default target.
#pragma GCC diagnostic ignored "-Wpsabi"

#include "classify/Classify.h"

#include "util/Lanes.h"
#include "util/SetBits.h"

#include <fluidsurf/Error.h>

#include <tbb/parallel_for.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <utility>

namespace fluidsurf {
namespace classify {

namespace {

/// A particle closer than this many h (per axis) to the last one of its cell whose sums were
/// computed shares them (2^-12 h: 1e-3 r for h = 4r).
constexpr double kSameSpot = 1.0 / 4096;

bool sameSpot(const Vec3f& a, const Vec3f& b, float tolerance)
{
    return std::fabs(a.x - b.x) <= tolerance && std::fabs(a.y - b.y) <= tolerance &&
           std::fabs(a.z - b.z) <= tolerance;
}

/// The candidates of one cell (the particles of the cells its box reaches, in that order),
/// padded to a multiple of kClassLanes, in groups of kClassLanes (group g: candidates
/// [g kClassLanes, (g + 1) kClassLanes), one a lane), and each group's bounds. A particle sums
/// only the groups whose bounds come within h of it (liveGroups): a group out of reach would
/// add exact zeros to every lane, and the cell's box reaches about twice as far as a particle
/// does (13.7 groups a particle, 7.0 of them live, on the 1.7M-particle frame; 27.1 and 11.0
/// on the 13.1M drop). The arrays keep their size between cells: set, not pushed.
struct Neighbourhood
{
    std::vector<float> x, y, z, v;
    /// per group, padded to a multiple of util::kWideLanes with groups out of every reach
    std::vector<float> x0, x1, y0, y1, z0, z1;

    /// The particles of index's cells overlapping [lo, hi] (CellIndex::forEachCellInBox's
    /// order), relative to o; volumes from the radii, or uniformVolume without them. Inlined
    /// into each register width's cell loop (classifyCells): its loops over the candidates are
    /// vectorised there, an AVX register at a time where the CPU has AVX2. Each coordinate is
    /// c - o in float whatever the width, which is the device's float(double(c) - double(o))
    /// bit for bit: the difference of two floats rounded once to double (53 bits) and then
    /// to float (24) is the float difference rounded once, as 53 >= 2 * 24 + 1 (Figueroa,
    /// "When is double rounding innocuous?", 1995). In one pass with the copy, instead of a
    /// second pass in doubles. (The gather was half of classification's time on the 13.1M
    /// drop, a cell's 216 candidates serving its 8 particles.)
    template <bool kWide>
    __attribute__((always_inline)) inline void
    gather(const neighbors::CellIndex& index, neighbors::NearbyCells& cells, const double lo[3],
           const double hi[3], const Vec3f& o, double uniformVolume)
    {
        constexpr float kFar = 3e38f; // (h^2 - d^2 < 0 for anything this far: an exact zero)
        mRanges.clear();
        size_t m = 0;
        cells.forEachCellInBox(lo, hi, [&](uint32_t b, uint32_t e) {
            mRanges.push_back(uint64_t(e) << 32 | b);
            m += e - b;
        });
        const size_t size = (m + kClassLanes - 1) / kClassLanes * kClassLanes;
        // x, y, z: room for the 8 a wide copy may write past a cell's last particle (the next
        // cell's copy or the padding below writes over them; no group reads beyond size)
        for (std::vector<float>* c : {&x, &y, &z})
            c->resize(size + kCopyLanes);
        v.resize(size);
        float *xs = x.data(), *ys = y.data(), *zs = z.data(), *vs = v.data();
        size_t k = 0;
        const size_t particles = index.positions.size();
        for (const uint64_t r : mRanges) {
            const uint32_t first = uint32_t(r), n = uint32_t(r >> 32) - first;
            const Vec3f* p = &index.positions[first];
            size_t j = 0;
            if constexpr (kWide) // 8 at a time while 8 are there to read (past the cell's end too)
                for (; j < n && first + j + kCopyLanes <= particles; j += kCopyLanes)
                    copyRelative8(&p[j], o, &xs[k + j], &ys[k + j], &zs[k + j]);
            for (; j < n; ++j)
                xs[k + j] = p[j].x - o.x, ys[k + j] = p[j].y - o.y, zs[k + j] = p[j].z - o.z;
            if (!index.radii.empty()) {
                const float* rs = &index.radii[first];
                for (size_t j = 0; j < n; ++j) {
                    const double rj = rs[j];
                    vs[k + j] = float(8 * rj * rj * rj);
                }
            }
            k += n;
        }
        if (index.radii.empty()) std::fill(vs, vs + m, float(uniformVolume));
        for (; k < size; ++k)
            xs[k] = ys[k] = zs[k] = kFar, vs[k] = 0;
        const size_t groups = size / kClassLanes;
        const size_t padded = (groups + util::kWideLanes - 1) / util::kWideLanes * util::kWideLanes;
        for (std::vector<float>* c : {&x0, &x1, &y0, &y1, &z0, &z1})
            c->resize(padded);
        size_t g = 0;
        if constexpr (kWide) // 8 groups at a time while 8 are there
            for (; g + kClassLanes <= groups; g += kClassLanes) {
                bounds8(xs, g, &x0[g], &x1[g]);
                bounds8(ys, g, &y0[g], &y1[g]);
                bounds8(zs, g, &z0[g], &z1[g]);
            }
        for (; g < groups; ++g) {
            bound(xs, g, x0[g], x1[g]);
            bound(ys, g, y0[g], y1[g]);
            bound(zs, g, z0[g], z1[g]);
        }
        for (size_t g = groups; g < padded; ++g)
            x0[g] = x1[g] = y0[g] = y1[g] = z0[g] = z1[g] = kFar;
    }

private:
    static constexpr size_t kCopyLanes = 8;

    /// p[0, 8)'s coordinates less o's, into x, y and z: the scalar loop's subtractions, in AVX
    /// registers. The 24 floats of 8 points are six 4-float loads, points 0-3 in the registers'
    /// low halves and 4-7 in their high halves, so that five shuffles within the halves sort
    /// them into the three axes (the same moves on both halves). (One point at a time, the copy
    /// was a fifth of classification's samples on the 13.1M drop, a cell's 216 candidates for
    /// its 8 particles. From three 8-float loads it took eight shuffles across the halves and
    /// five mask loads: a sixth of the samples still.)
    __attribute__((always_inline)) static void copyRelative8(const Vec3f* p, const Vec3f& o,
                                                             float* x, float* y, float* z)
    {
        static_assert(sizeof(Vec3f) == 3 * sizeof(float));
        typedef float Four __attribute__((vector_size(16)));
        using V = util::WideLanes;
        const float* f = reinterpret_cast<const float*>(p);
        Four q[6];
        for (int k = 0; k < 6; ++k)
            std::memcpy(&q[k], f + 4 * k, sizeof q[k]);
        auto halves = [](Four lo, Four hi) -> V {
            return __builtin_shufflevector(lo, hi, 0, 1, 2, 3, 4, 5, 6, 7);
        };
        const V m14 = halves(q[0], q[3]); // x0 y0 z0 x1 | x4 y4 z4 x5
        const V m25 = halves(q[1], q[4]); // y1 z1 x2 y2 | y5 z5 x6 y6
        const V m36 = halves(q[2], q[5]); // z2 x3 y3 z3 | z6 x7 y7 z7
        const V xy = __builtin_shufflevector(m25, m36, 2, 3, 9, 10, 6, 7, 13, 14); // x2 y2 x3 y3
        const V yz = __builtin_shufflevector(m14, m25, 1, 2, 8, 9, 5, 6, 12, 13);  // y0 z0 y1 z1
        const V rx = __builtin_shufflevector(m14, xy, 0, 3, 8, 10, 4, 7, 12, 14) - o.x;
        const V ry = __builtin_shufflevector(yz, xy, 0, 2, 9, 11, 4, 6, 13, 15) - o.y;
        const V rz = __builtin_shufflevector(yz, m36, 1, 3, 8, 11, 5, 7, 12, 15) - o.z;
        std::memcpy(x, &rx, sizeof rx);
        std::memcpy(y, &ry, sizeof ry);
        std::memcpy(z, &rz, sizeof rz);
    }

    /// The least and largest of group g's coordinates c (two registers of util::kLanes)
    __attribute__((always_inline)) static void bound(const float* c, size_t g, float& lo, float& hi)
    {
        static_assert(kClassLanes == 2 * util::kLanes);
        const util::Lanes a = util::loadLanes(&c[g * kClassLanes]),
                          b = util::loadLanes(&c[g * kClassLanes + util::kLanes]);
        const util::Lanes l = a < b ? a : b, u = a < b ? b : a;
        lo = std::min(std::min(l[0], l[1]), std::min(l[2], l[3]));
        hi = std::max(std::max(u[0], u[1]), std::max(u[2], u[3]));
    }

    /// bound() for groups [g, g + 8) at once, in AVX registers (inlined into the AVX2 instance):
    /// each group's 8 coordinates halved, quartered and paired down by shuffles, so that one
    /// minimum and one maximum serve 8, 4 and then 2 groups a step. The same least and largest
    /// coordinates (a minimum's order changes at most the sign of a zero, which no reach test
    /// sees). One group at a time, its horizontal minimum and maximum were a tenth of
    /// classification's samples (the 13.1M drop), 27 groups for a cell's 8 particles.
    __attribute__((always_inline)) static void bounds8(const float* c, size_t g, float* lo,
                                                       float* hi)
    {
        static_assert(kClassLanes == util::kWideLanes);
        using V = util::WideLanes;
        auto low = [](V a, V b) { return a < b ? a : b; };  // (vminps)
        auto high = [](V a, V b) { return b < a ? a : b; }; // (vmaxps)
        // (each group loaded into a register of its own: copied as one block to the stack, the
        // loads that followed waited on the copy's stores)
        auto group = [&](int k) {
            V v;
            std::memcpy(&v, &c[(g + size_t(k)) * kClassLanes], sizeof v);
            return v;
        };
        // groups 2k and 2k + 1: the low halves beside each other, then the high halves
        V m[4], M[4];
        for (int k = 0; k < 4; ++k) {
            const V u = group(2 * k), w = group(2 * k + 1);
            const V a = __builtin_shufflevector(u, w, 0, 1, 2, 3, 8, 9, 10, 11),
                    b = __builtin_shufflevector(u, w, 4, 5, 6, 7, 12, 13, 14, 15);
            m[k] = low(a, b), M[k] = high(a, b); // lanes 0-3: group 2k's, 4-7: 2k + 1's
        }
        // two lanes a group: 4k, 4k + 2 in lanes 0-3, 4k + 1, 4k + 3 in 4-7
        auto pairs = [](V a, V b, auto f) {
            return f(__builtin_shufflevector(a, b, 0, 1, 8, 9, 4, 5, 12, 13),
                     __builtin_shufflevector(a, b, 2, 3, 10, 11, 6, 7, 14, 15));
        };
        const V n0 = pairs(m[0], m[1], low), n1 = pairs(m[2], m[3], low);
        const V N0 = pairs(M[0], M[1], high), N1 = pairs(M[2], M[3], high);
        // one lane a group: 0, 4, 2, 6, 1, 5, 3, 7, then in order
        auto ones = [](V a, V b, auto f) {
            const V r = f(__builtin_shufflevector(a, b, 0, 8, 2, 10, 4, 12, 6, 14),
                          __builtin_shufflevector(a, b, 1, 9, 3, 11, 5, 13, 7, 15));
            return __builtin_shufflevector(r, r, 0, 4, 2, 6, 1, 5, 3, 7);
        };
        const V l = ones(n0, n1, low), h = ones(N0, N1, high);
        std::memcpy(lo, &l, sizeof l);
        std::memcpy(hi, &h, sizeof h);
    }

    /// The cells' particles, end << 32 | begin: one 64-bit store and load each (as a pair of
    /// two 32-bit stores read back at once, the store could not be forwarded to the load: a
    /// stall per cell, 8% of the cell loop's samples).
    std::vector<uint64_t> mRanges;
};

/// Per lane, a group's float distance to (its bounds lo, hi on one axis) from p, 0 inside.
template <typename V>
__attribute__((always_inline)) inline V reachOf(const float* lo, const float* hi, float p)
{
    V l, h;
    std::memcpy(&l, lo, sizeof l);
    std::memcpy(&h, hi, sizeof h);
    const V below = l - p, above = p - h;
    const V e = below > above ? below : above;
    return e > 0.f ? e : V{};
}

/// The groups of nb that may hold a candidate closer than h to (px, py, pz), into `live`, in
/// order; returns how many. A group left out adds nothing to the sums: each lane's d^2 =
/// dx dx + dy dy + dz dz is at least the group's (ex ex + ey ey) + ez ez below, e the float
/// distance to the bounds per axis (float subtraction, squares and sums are monotonic), so
/// when that is >= h^2, every lane's t is 0, its count 0 and every product an exact +-0; a sum
/// that starts at +0 is never -0, and x + (+-0) = x. So the lanes hold the same bits as with
/// every group, which the device sums (cuda/src/Classify.cu). V: the groups tested at once (4
/// or 8; the same list either way).
template <typename V>
__attribute__((always_inline)) inline size_t liveGroups(const Neighbourhood& nb, float px, float py,
                                                        float pz, float h2, uint32_t* live)
{
    constexpr int kWidth = sizeof(V) / sizeof(float);
    size_t n = 0;
    for (size_t g = 0; g < nb.x0.size(); g += kWidth) {
        const V ex = reachOf<V>(&nb.x0[g], &nb.x1[g], px),
                ey = reachOf<V>(&nb.y0[g], &nb.y1[g], py),
                ez = reachOf<V>(&nb.z0[g], &nb.z1[g], pz);
        const auto near = ex * ex + ey * ey + ez * ez < h2;
        if constexpr (kWidth == 8) {
            // The live lanes' numbers from a table by their mask, all written at once (one at
            // a time, each lane's flag extracted, this was a twentieth of classification's
            // samples).
            // live has room: n <= g, and nb.x0.size() is a multiple of 8. The mask in one
            // instruction (vmovmskps: this instance only runs inlined into the AVX2 loop), where
            // a reduction by shuffles took eight.
            typedef int32_t Ints __attribute__((vector_size(32)));
            const unsigned mask = unsigned(__builtin_ia32_movmskps256(V(near)));
            Ints numbers;
            std::memcpy(&numbers, util::kSetBits.positions[mask], sizeof numbers);
            numbers += int32_t(g);
            std::memcpy(&live[n], &numbers, sizeof numbers);
            n += util::kSetBits.count[mask];
        } else {
            for (int l = 0; l < kWidth; ++l)
                live[n] = uint32_t(g + l), n += near[l] != 0; // no branch: half are live
        }
    }
    return n;
}

/// One particle's neighbour sums, lane by lane (ClassRule.h).
struct LaneSums
{
    float count[kClassLanes], cf[kClassLanes], gx[kClassLanes], gy[kClassLanes], gz[kClassLanes];
};

/// The sums of the particle at p over the neighbourhood's live groups, on kClassLanes lanes
/// held in N vectors V (lanes 0-3 in the first of two SSE registers, 4-7 in the second): the
/// same operations on every lane whatever V is, and no FMA (neither target has it), so the
/// sums are the device's (cuda/src/Classify.cu) bit for bit.
template <typename V, int N>
__attribute__((always_inline)) inline void laneSums(const Neighbourhood& nb, const uint32_t* live,
                                                    size_t nLive, float px, float py, float pz,
                                                    float h2, LaneSums& out)
{
    constexpr int kWidth = kClassLanes / N; // floats in a V
    typedef int32_t Ints __attribute__((vector_size(sizeof(V))));
    // The counts in integers: a lane within h is one mask for both the count and t, counted by
    // subtracting the mask (-1). t = h2 - d2 is > 0 exactly where d2 < h2: the difference of
    // two floats is 0 only for equal ones (near each other it is exact, a multiple of their
    // spacing: a subnormal only for h below 1e-15, so not even a flush to zero changes it).
    // The same whole numbers as adding 1.f (the device's way): exact either way, far below 2^24.
    // Two vector operations fewer of the loop's 24.
    Ints count[N]{};
    V cf[N]{}, gx[N]{}, gy[N]{}, gz[N]{};
    for (size_t i = 0; i < nLive; ++i)
        for (int k = 0; k < N; ++k) {
            const size_t j = size_t(live[i]) * kClassLanes;
            V x, y, z, v;
            std::memcpy(&x, &nb.x[j + k * kWidth], sizeof x);
            std::memcpy(&y, &nb.y[j + k * kWidth], sizeof y);
            std::memcpy(&z, &nb.z[j + k * kWidth], sizeof z);
            std::memcpy(&v, &nb.v[j + k * kWidth], sizeof v);
            const V dx = x - px, dy = y - py, dz = z - pz;
            const V d2 = dx * dx + dy * dy + dz * dz;
            V t = h2 - d2;
            const Ints near = t > 0.f;
            t = near ? t : V{};
            count[k] -= near;
            const V vt2 = v * t * t;
            cf[k] += vt2 * t;
            gx[k] += vt2 * dx, gy[k] += vt2 * dy, gz[k] += vt2 * dz;
        }
    for (int k = 0; k < N; ++k) {
        const V c = __builtin_convertvector(count[k], V);
        std::memcpy(&out.count[k * kWidth], &c, sizeof c);
    }
    std::memcpy(out.cf, cf, sizeof cf);
    std::memcpy(out.gx, gx, sizeof gx), std::memcpy(out.gy, gy, sizeof gy);
    std::memcpy(out.gz, gz, sizeof gz);
}

/// classifyLanes(s...) with the lanes added up in AVX registers: (count, cf, gx, gy) of lane l
/// as one vector of four doubles, the vectors added in lane order from +0, which is each
/// scalar sum's order (gz alone, as classifyLanes adds it). One by one, the 40 conversions and
/// additions and the moves between them were a tenth of classification's samples.
__attribute__((always_inline)) inline ParticleSums classifyWide(const LaneSums& s,
                                                                const ClassRule& rule)
{
    typedef double Doubles4 __attribute__((vector_size(32)));
    typedef float Floats4 __attribute__((vector_size(16)));
    util::WideLanes c, f, x, y;
    std::memcpy(&c, s.count, sizeof c), std::memcpy(&f, s.cf, sizeof f);
    std::memcpy(&x, s.gx, sizeof x), std::memcpy(&y, s.gy, sizeof y);
    // (lanes k of c and f, or of x and y, side by side in pairs, within each 128-bit half)
    const util::WideLanes cf0 = __builtin_shufflevector(c, f, 0, 8, 1, 9, 4, 12, 5, 13),
                          cf1 = __builtin_shufflevector(c, f, 2, 10, 3, 11, 6, 14, 7, 15),
                          xy0 = __builtin_shufflevector(x, y, 0, 8, 1, 9, 4, 12, 5, 13),
                          xy1 = __builtin_shufflevector(x, y, 2, 10, 3, 11, 6, 14, 7, 15);
    // t[k]: lane k's (count, cf, gx, gy) in its low half, lane k + 4's in its high half
    const util::WideLanes t[4] = {__builtin_shufflevector(cf0, xy0, 0, 1, 8, 9, 4, 5, 12, 13),
                                  __builtin_shufflevector(cf0, xy0, 2, 3, 10, 11, 6, 7, 14, 15),
                                  __builtin_shufflevector(cf1, xy1, 0, 1, 8, 9, 4, 5, 12, 13),
                                  __builtin_shufflevector(cf1, xy1, 2, 3, 10, 11, 6, 7, 14, 15)};
    static_assert(kClassLanes == 8);
    Doubles4 sum{}; // +0, as classifyLanes starts
    for (int half = 0; half < 2; ++half)
        for (int k = 0; k < 4; ++k) {
            Floats4 lane;
            std::memcpy(&lane, reinterpret_cast<const float*>(&t[k]) + 4 * half, sizeof lane);
            sum += __builtin_convertvector(lane, Doubles4);
        }
    double gz = 0;
    for (int l = 0; l < kClassLanes; ++l)
        gz += s.gz[l];
    const double g[3] = {sum[2], sum[3], gz};
    return classifyTotals(sum[0], sum[1], g, rule);
}

/// What classifyCells reads and writes.
struct CellWork
{
    const neighbors::CellIndex& index;
    double h, uniformVolume;
    float h2;
    ClassRule rule;
    bool withSums, withNormals;
    Classification& out;
};

/// The particles of cells [begin, end): each cell gathers its neighbourhood once, then each of
/// its particles sums the live groups. V, N: the sums' registers (see laneSums); the gather and
/// the groups' reach run in registers as wide as V.
template <typename V, int N>
__attribute__((always_inline)) inline void classifyCells(const CellWork& w, size_t begin,
                                                         size_t end)
{
    const neighbors::CellIndex& index = w.index;
    Classification& out = w.out;
    const double h = w.h;
    const float h2 = w.h2;
    Neighbourhood nb;
    neighbors::NearbyCells nearby(index);
    std::vector<uint32_t> live;
    for (size_t c = begin; c != end; ++c) {
        const uint32_t b = index.starts[c], e = index.starts[c + 1];
        // Box of the cell's particles, widened by h: everything any of them can reach.
        // Coordinates relative to the first particle keep float rounding small.
        const Vec3f o = index.positions[b];
        double lo[3] = {o.x, o.y, o.z}, hi[3] = {o.x, o.y, o.z};
        for (uint32_t i = b; i < e; ++i)
            for (int a = 0; a < 3; ++a) {
                lo[a] = std::min(lo[a], double(index.positions[i][a]));
                hi[a] = std::max(hi[a], double(index.positions[i][a]));
            }
        for (int a = 0; a < 3; ++a)
            lo[a] -= h, hi[a] += h;
        constexpr bool kWide = sizeof(V) == 8 * sizeof(float); // the AVX2 instance
        nb.gather<kWide>(index, nearby, lo, hi, o, w.uniformVolume);
        live.resize(nb.x0.size());
        uint32_t computed = b;
        for (uint32_t i = b; i < e; ++i) {
            const Vec3f& p = index.positions[i];
            // A particle at the spot of the last computed one has its sums: coincident
            // particles (a degenerate frame piles 1e5 on one point, often with a little
            // noise) cost one neighbourhood pass per spot instead of one each. No two
            // particles of a real fluid come within kSameSpot * h of each other, so
            // real frames are computed particle by particle as before.
            if (i > b && sameSpot(p, index.positions[computed], float(h * kSameSpot))) {
                if (w.withSums) {
                    out.neighbours[i] = out.neighbours[computed];
                    out.colorField[i] = out.colorField[computed];
                    out.colorGradient[i] = out.colorGradient[computed];
                }
                out.classes[i] = out.classes[computed];
                if (w.withNormals) out.normals[i] = out.normals[computed];
                continue;
            }
            computed = i;
            const float px = p.x - o.x, py = p.y - o.y, pz = p.z - o.z; // (see Neighbourhood)
            const size_t nLive = liveGroups<V>(nb, px, py, pz, h2, live.data());
            LaneSums sums;
            laneSums<V, N>(nb, live.data(), nLive, px, py, pz, h2, sums);
            ParticleSums ps;
            if constexpr (kWide)
                ps = classifyWide(sums, w.rule);
            else
                ps = classifyLanes(sums.count, sums.cf, sums.gx, sums.gy, sums.gz, w.rule);
            if (w.withSums) {
                out.neighbours[i] = ps.neighbours;
                out.colorField[i] = ps.colorField;
                out.colorGradient[i] = ps.gradient;
            }
            out.classes[i] = ps.cls;
            if (w.withNormals && isSurface(ps.cls)) {
                // The gradient's sum points into the fluid (d = x_j - x_i).
                double g[3] = {0, 0, 0};
                for (int l = 0; l < kClassLanes; ++l)
                    g[0] += sums.gx[l], g[1] += sums.gy[l], g[2] += sums.gz[l];
                const double len = std::sqrt(g[0] * g[0] + g[1] * g[1] + g[2] * g[2]);
                if (len > 0)
                    out.normals[i] =
                        Vec3f(float(-g[0] / len), float(-g[1] / len), float(-g[2] / len));
            }
        }
    }
}

/// classifyCells in AVX registers, where the CPU has AVX2 (the sums in half the loop of two SSE
/// registers, the gather and the reach in twice the width): compiled for that target alone and
/// picked at run time, so the build runs on any x86-64. No FMA: the device's bits.
__attribute__((target("avx2"))) void wideCells(const CellWork& w, size_t begin, size_t end)
{
    classifyCells<util::WideLanes, 1>(w, begin, end);
}

void narrowCells(const CellWork& w, size_t begin, size_t end)
{
    classifyCells<util::Lanes, 2>(w, begin, end);
}

} // namespace

KernelConstants kernelConstants(const Params& params)
{
    KernelConstants k;
    k.h = params.smoothingLength;
    k.h2 = float(k.h * k.h);
    k.poly6 = 315.0 / (64.0 * M_PI * std::pow(k.h, 9));
    k.gradientScale = 6 * k.poly6 * k.h;
    k.uniformVolume = std::pow(2 * params.radius, 3);
    return k;
}

ClassRule classRule(const Params& params)
{
    const KernelConstants k = kernelConstants(params);
    ClassRule r;
    r.poly6 = k.poly6, r.gradientScale = k.gradientScale;
    r.splashNeighbours = params.splashNeighbours, r.surfaceNeighbours = params.surfaceNeighbours;
    r.colorFieldThreshold = params.colorFieldThreshold,
    r.colorGradientThreshold = params.colorGradientThreshold;
    return r;
}

int classifyRegisterLanes()
{
    static const bool wide = __builtin_cpu_supports("avx2");
    return wide ? util::kWideLanes : util::kLanes;
}

Classification classifyParticles(const neighbors::CellIndex& index, const Params& params,
                                 Context& ctx, Outputs outputs, int registerLanes)
{
    if (registerLanes != util::kLanes && registerLanes != util::kWideLanes)
        throw ValueError("classifyParticles: registerLanes must be 4 or 8");
    if (registerLanes == util::kWideLanes && classifyRegisterLanes() != registerLanes)
        throw ValueError("classifyParticles: 8 lanes a register need a CPU with AVX2");
    const size_t n = index.size();
    Classification out;
    // each written by the loop below, every particle's, where its cell is done
    out.classes.resize(n);
    if (outputs.sums) {
        out.neighbours.resize(n);
        out.colorField.resize(n);
        out.colorGradient.resize(n);
    }
    if (outputs.normals) out.normals.assign(n, Vec3f(0, 0, 0));
    const KernelConstants k = kernelConstants(params);
    static_assert(kClassLanes == util::kWideLanes && kClassLanes == 2 * util::kLanes);
    const CellWork work{
        index, k.h, k.uniformVolume, k.h2, classRule(params), outputs.sums, outputs.normals, out};
    const auto cellsOf = registerLanes == util::kWideLanes ? wideCells : narrowCells;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, index.cellCount(), 16),
                      [&](const tbb::blocked_range<size_t>& cells) {
                          ctx.checkpoint();
                          cellsOf(work, cells.begin(), cells.end());
                      });
    // The classes counted on all threads: on one, the 13.1M drop's took 25 ms of a 16-thread
    // run (an H100 host), the others idle.
    using Counts = std::array<size_t, 4>; // by ParticleClass
    const Counts counts = tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, n, size_t(1) << 16), Counts{},
        [&](const tbb::blocked_range<size_t>& r, Counts sum) {
            for (size_t i = r.begin(); i != r.end(); ++i)
                ++sum[out.classes[i] & 3];
            return sum;
        },
        [](Counts a, const Counts& b) {
            for (size_t k = 0; k < a.size(); ++k)
                a[k] += b[k];
            return a;
        });
    out.interior = counts[Interior], out.surface = counts[Surface];
    out.splash = counts[Splash], out.isolated = counts[Isolated];
    return out;
}

std::vector<uint8_t> notIsolated(const Classification& c)
{
    std::vector<uint8_t> keep(c.classes.size());
    tbb::parallel_for(tbb::blocked_range<size_t>(0, keep.size(), size_t(1) << 16),
                      [&](const tbb::blocked_range<size_t>& r) {
                          for (size_t i = r.begin(); i != r.end(); ++i)
                              keep[i] = c.classes[i] != Isolated;
                      });
    return keep;
}

void selectClasses(Classification& c, const std::vector<uint8_t>& keep)
{
    selectInPlace(c.classes, keep);
    selectInPlace(c.neighbours, keep);
    selectInPlace(c.colorField, keep);
    selectInPlace(c.colorGradient, keep);
    selectInPlace(c.normals, keep);
}

} // namespace classify
} // namespace fluidsurf
