// CollapseBatchTest.cc - several edges' collapses at once (post/CollapseBatch) against one at a
// time: the same bits in every lane (errors and points), on both register widths, for quadrics of
// random planes and for the cases the selects decide (no planes, a single plane, parallel planes, a
// zero weight).
#include "post/CollapseBatch.h"

#include <fluidsurf/Error.h>

#include <gtest/gtest.h>

#include <cstring>
#include <random>
#include <vector>

using fluidsurf::Vec3d;
using fluidsurf::post::Quadric;
using fluidsurf::post::detail::bestCollapse;
using fluidsurf::post::detail::CollapseBatch;

namespace {

struct End
{
    Quadric q;
    Vec3d p;
};

/// k planes through points near p (k = 0: none), unit normals, area weights; `parallel`: all
/// with one normal (a singular matrix, decided by the pull).
End randomEnd(std::mt19937_64& rng, int k, bool parallel)
{
    std::uniform_real_distribution<double> u(-1, 1);
    End e{Quadric{}, Vec3d(u(rng), u(rng), u(rng))};
    Vec3d n0(u(rng), u(rng), u(rng) + 2);
    n0.normalize();
    for (int i = 0; i < k; ++i) {
        Vec3d n = parallel ? n0 : Vec3d(u(rng), u(rng), u(rng) + 1.5);
        n.normalize();
        e.q += Quadric::plane(n, Vec3d(u(rng), u(rng), u(rng)) * 0.1, 0.01 + 0.5 * (u(rng) + 1));
    }
    return e;
}

bool sameBits(double a, double b)
{
    return std::memcmp(&a, &b, sizeof a) == 0;
}

} // namespace

TEST(CollapseBatch, EveryLaneGivesTheBitsOfOneEdgeAlone)
{
    std::mt19937_64 rng(11);
    std::vector<int> widths{2};
    if (CollapseBatch::registerLanes() == 4) widths.push_back(4);
    size_t edges = 0, errorsAboveZero = 0;
    for (int width : widths)
        for (int round = 0; round < 4000; ++round) {
            CollapseBatch batch;
            const int n = 1 + round % CollapseBatch::kSize;
            double expected[CollapseBatch::kSize];
            Vec3d expectedPoint[CollapseBatch::kSize];
            for (int l = 0; l < n; ++l) {
                const int kind = (round + l) % 7; // 0: no planes; 1, 2: parallel; else random
                const End a = randomEnd(rng, kind == 0 ? 0 : 1 + (round + 3 * l) % 6, kind <= 2);
                End b = randomEnd(rng, kind == 0 ? 0 : 1 + (round + l) % 5, kind <= 2);
                if (kind == 3) b.q.w = 0; // weightless: error 0 by the select
                batch.set(l, a.q, a.p, b.q, b.p);
                const auto one = bestCollapse(a.q, a.p, b.q, b.p);
                expected[l] = one.error, expectedPoint[l] = one.point;
            }
            double got[CollapseBatch::kSize];
            batch.errors(n, got, width);
            fluidsurf::post::detail::Collapse found[CollapseBatch::kSize];
            batch.collapses(n, found, width); // the points too (the decimation's heap keeps them)
            for (int l = 0; l < n; ++l) {
                EXPECT_TRUE(sameBits(got[l], expected[l]))
                    << "width " << width << ", round " << round << ", lane " << l << ": " << got[l]
                    << " against " << expected[l];
                EXPECT_TRUE(sameBits(found[l].error, expected[l])) << round << ", lane " << l;
                for (int k = 0; k < 3; ++k)
                    EXPECT_TRUE(sameBits(found[l].point[k], expectedPoint[l][k]))
                        << "width " << width << ", round " << round << ", lane " << l << ", axis "
                        << k << ": " << found[l].point[k] << " against " << expectedPoint[l][k];
                ++edges, errorsAboveZero += expected[l] > 0;
            }
        }
    // the random planes do not meet in one point: most collapses have an error to compare
    EXPECT_GT(errorsAboveZero, edges / 2);
}

TEST(CollapseBatch, TheErrorIsTheLeastOnTheEdgesLine)
{
    // independent of the batch's arithmetic: the collapse's point minimises the merged planes'
    // error plus the pull eps |y - middle|^2 (Quadric::minimizer), so its error is no more than
    // that sum at either end or at the middle
    std::mt19937_64 rng(5);
    for (int i = 0; i < 500; ++i) {
        const End a = randomEnd(rng, 4, false), b = randomEnd(rng, 4, false);
        CollapseBatch batch;
        batch.set(0, a.q, a.p, b.q, b.p);
        double e;
        batch.errors(1, &e);
        const Quadric q = a.q + b.q.movedTo(a.p - b.p); // both about a.p
        const double eps = 1e-3 * (q.a00 + q.a11 + q.a22);
        const Vec3d middle = (b.p - a.p) * 0.5;
        for (const Vec3d& y : {Vec3d(0.0), b.p - a.p, middle})
            EXPECT_LE(e * q.w, (q.error(y) + eps * (y - middle).lengthSqr()) * (1 + 1e-9) + 1e-15)
                << i;
    }
}

TEST(CollapseBatch, RefusesFourLanesWithoutAvx2)
{
    CollapseBatch batch;
    double e[CollapseBatch::kSize];
    if (CollapseBatch::registerLanes() == 4)
        EXPECT_NO_THROW(batch.errors(4, e, 4));
    else
        EXPECT_THROW(batch.errors(4, e, 4), fluidsurf::ValueError);
    EXPECT_THROW(batch.errors(4, e, 3), fluidsurf::ValueError);
    fluidsurf::post::detail::Collapse c[CollapseBatch::kSize];
    EXPECT_THROW(batch.collapses(4, c, 3), fluidsurf::ValueError);
}
