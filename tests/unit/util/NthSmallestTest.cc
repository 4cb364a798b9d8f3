// NthSmallestTest.cc - util::nthSmallest against std::nth_element on the accepted values: the
// same value for every k, with repeats, zeros, values in one histogram bucket and values the
// predicate leaves out, and false once k reaches the accepted count.
#include "util/NthSmallest.h"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <limits>
#include <random>
#include <vector>

using fluidsurf::util::nthSmallest;

namespace {

/// What nthSmallest must give: the accepted values copied out, then std::nth_element.
template <typename Accept>
bool reference(const std::vector<float>& v, Accept accept, size_t k, float& out)
{
    std::vector<float> kept;
    for (float x : v)
        if (accept(x)) kept.push_back(x);
    if (k >= kept.size()) return false;
    std::nth_element(kept.begin(), kept.begin() + k, kept.end());
    out = kept[k];
    return true;
}

} // namespace

TEST(NthSmallest, SameValueAsNthElementForEveryKindOfInput)
{
    std::mt19937 rng(7);
    const float inf = std::numeric_limits<float>::infinity();
    auto underOne = [](float x) { return x <= 1.0f && std::isfinite(x); };
    for (const size_t n : {size_t(0), size_t(1), size_t(7), size_t(1000), size_t(300000)}) {
        for (int kind = 0; kind < 4; ++kind) {
            std::vector<float> v(n);
            std::uniform_real_distribution<float> spread(0.f, 2.f);
            for (size_t i = 0; i < n; ++i) {
                switch (kind) {
                case 0:
                    v[i] = spread(rng);
                    break; // wide
                case 1:
                    v[i] = float(rng() % 17) / 16.f;
                    break; // repeats, 0
                case 2:
                    v[i] = 0.5f + float(rng() % 1000) * 1e-9f;
                    break; // one bucket
                default:
                    v[i] = rng() % 3 == 0 ? inf : std::ldexp(1.f, -int(rng() % 60)); // tiny
                }
            }
            size_t accepted = 0;
            for (float x : v)
                accepted += underOne(x);
            for (const size_t k : {size_t(0), accepted / 3, accepted / 2,
                                   accepted ? accepted - 1 : 0, accepted, accepted + 5}) {
                float want = -1.f, got = -1.f;
                const bool expected = reference(v, underOne, k, want);
                EXPECT_EQ(nthSmallest(v.data(), v.size(), underOne, k, got), expected)
                    << "n " << n << ", kind " << kind << ", k " << k;
                if (expected) EXPECT_EQ(got, want) << "n " << n << ", kind " << kind << ", k " << k;
            }
        }
    }
}
