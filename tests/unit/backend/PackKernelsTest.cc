// The anisotropic kernels as they travel to the GPU (backend/PackKernels.h): unpacked by a plain
// search for each kernel's last fresh entry, every kernel's a, extent and weight come back bit
// for bit; the fresh bits are exactly the kernels that differ from the one before; the word
// counts add up. On a pipeline's own table (a jittered drop: interior spheres) and on made-up
// tables at the words' edges.
#include "backend/PackKernels.h"
#include "unit/field/PipelineKernels.h"

#include <fluidsurf/Scenes.h>

#include <gtest/gtest.h>

#include <tbb/global_control.h>

#include <cmath>
#include <cstring>
#include <random>

using namespace fluidsurf;

namespace {

/// Every kernel's entry from the packing, against the table, bit for bit; returns the kernels
/// whose bit is set.
size_t expectUnpacksTo(const backend::PackedKernels& p, const field::AnisotropicKernels& t)
{
    const size_t n = t.extent.size() / 3;
    EXPECT_EQ(p.fresh.size(), (n + 31) / 32);
    EXPECT_EQ(p.freshBefore.size(), p.fresh.size());
    EXPECT_EQ(p.a.size(), 6 * p.freshCount());
    EXPECT_EQ(p.weight.size(), t.weight.empty() ? 0 : p.freshCount());
    size_t set = 0;
    long last = -1; // the last fresh entry so far
    for (size_t j = 0; j < n; ++j) {
        if (j % 32 == 0) EXPECT_EQ(p.freshBefore[j / 32], set) << "word " << j / 32;
        const bool fresh = (p.fresh[j / 32] >> (j % 32)) & 1u;
        bool differs = j == 0 ||
                       std::memcmp(&t.a[6 * j], &t.a[6 * j - 6], 6 * sizeof(float)) != 0 ||
                       std::memcmp(&t.extent[3 * j], &t.extent[3 * j - 3], 3 * sizeof(float)) != 0;
        if (!t.weight.empty())
            differs |= std::memcmp(&t.weight[j], &t.weight[j - (j > 0)], sizeof(float)) != 0;
        EXPECT_EQ(fresh, differs) << "kernel " << j;
        if (fresh) last = long(set++);
        if (last < 0 || size_t(last) >= p.freshCount()) {
            ADD_FAILURE() << "kernel " << j << " has no entry";
            return set;
        }
        EXPECT_EQ(std::memcmp(&p.a[6 * last], &t.a[6 * j], 6 * sizeof(float)), 0) << j;
        EXPECT_EQ(std::memcmp(&p.extent[3 * last], &t.extent[3 * j], 3 * sizeof(float)), 0) << j;
        if (!t.weight.empty())
            EXPECT_EQ(std::memcmp(&p.weight[last], &t.weight[j], sizeof(float)), 0) << j;
    }
    EXPECT_EQ(set, p.freshCount());
    for (size_t w = 0; w < p.fresh.size(); ++w) // no bits past the last kernel
        if (32 * w + 32 > n) EXPECT_EQ(p.fresh[w] >> (n - 32 * w), 0u);
    return set;
}

/// A table of n kernels, most one sphere, some with their own shape (and weights with yt10).
field::AnisotropicKernels madeUp(size_t n, double ownShare, bool weights, unsigned seed)
{
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.5f, 1.5f), pick(0, 1);
    field::AnisotropicKernels t;
    t.a.resize(6 * n), t.extent.resize(3 * n);
    if (weights) t.weight.resize(n);
    for (size_t j = 0; j < n; ++j) {
        const bool own = pick(rng) < ownShare;
        const float sphere[6] = {1, 0, 0, 1, 0, 1};
        for (int k = 0; k < 6; ++k)
            t.a[6 * j + k] = own ? u(rng) : sphere[k];
        for (int k = 0; k < 3; ++k)
            t.extent[3 * j + k] = own ? u(rng) : 0.1f;
        if (weights) t.weight[j] = own && pick(rng) < 0.5f ? u(rng) : 2.f;
    }
    return t;
}

} // namespace

TEST(PackKernels, MadeUpTablesAtTheWordsEdgesUnpackBitForBit)
{
    for (const size_t n : {size_t(0), size_t(1), size_t(31), size_t(32), size_t(33), size_t(64),
                           size_t(8191), size_t(8192), size_t(8193), size_t(40000)})
        for (const double share : {0.0, 0.1, 1.0})
            for (const bool weights : {false, true}) {
                SCOPED_TRACE(testing::Message()
                             << n << " kernels, " << share << " own, weights " << weights);
                const field::AnisotropicKernels t = madeUp(n, share, weights, unsigned(n + 7));
                const size_t set = expectUnpacksTo(backend::packKernels(t), t);
                if (share == 0.0) EXPECT_EQ(set, n > 0 ? 1u : 0u); // one sphere throughout
                if (share == 1.0) EXPECT_EQ(set, n);               // (u never repeats a float)
            }
}

TEST(PackKernels, ASignOrOneBitMakesAKernelFresh)
{
    field::AnisotropicKernels t = madeUp(100, 0.0, true, 3);
    t.a[6 * 40 + 1] = -0.f;                                           // -0 against +0
    t.extent[3 * 70 + 2] = std::nextafter(t.extent[3 * 70 + 2], 1.f); // one ulp
    t.weight[90] = std::nextafter(t.weight[90], 0.f);                 // the weight alone
    const backend::PackedKernels p = backend::packKernels(t);
    // 0, 40 and the one after it (back to the sphere), 70, 71, 90, 91.
    EXPECT_EQ(expectUnpacksTo(p, t), 7u);
}

TEST(PackKernels, APipelinesTableUnpacksOnAnyThreadCount)
{
    SceneParams sp;
    sp.radius = 0.025, sp.count = 30000, sp.jitter = 0.3, sp.seed = 11;
    const ParticleSet ps = generateScene(Scene::Drop, sp);
    for (const FieldKind kind : {FieldKind::Ssp07Aniso, FieldKind::Yt10}) {
        SCOPED_TRACE(fieldName(kind));
        Params p = Params::fromRadius(sp.radius);
        p.field = kind;
        Context ctx;
        const auto made = testing_support::pipelineKernels(ps, p, ctx);
        const field::AnisotropicKernels& t = made->table;
        const backend::PackedKernels many = backend::packKernels(t);
        const size_t set = expectUnpacksTo(many, t);
        // The drop's interior kernels are one sphere: at least the surface's are fresh, and far
        // from all of them.
        EXPECT_GE(set, made->shapes.stretched);
        EXPECT_LT(set, made->particles.centres.size() / 2);
        tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
        const backend::PackedKernels single = backend::packKernels(t);
        EXPECT_EQ(single.fresh, many.fresh);
        EXPECT_EQ(single.freshBefore, many.freshBefore);
        EXPECT_EQ(single.a, many.a);
        EXPECT_EQ(single.extent, many.extent);
        EXPECT_EQ(single.weight, many.weight);
    }
}
