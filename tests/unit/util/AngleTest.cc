// AngleTest.cc - util::angles against std::atan2: a corner's angle from its sides' cross and dot
// products, on random corners, nearly flat and nearly straight ones, and across scales.
#include "util/Angle.h"

#include "util/Lanes.h"

#include <fluidsurf/Error.h>

#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <vector>

using namespace fluidsurf;

namespace {

/// How many doubles apart a and b are (both >= 0).
int64_t ulpsApart(double a, double b)
{
    int64_t ia, ib;
    std::memcpy(&ia, &a, sizeof a);
    std::memcpy(&ib, &b, sizeof b);
    return ia > ib ? ia - ib : ib - ia;
}

/// (|a x b|, a . b) of random corners a, b in [-1, 1]^3 (a 64-bit LCG: the same on every
/// platform), every fourth of them made nearly flat, every fourth nearly straight, and every
/// fourth scaled by up to 1e+-20 on either side.
void corners(std::vector<double>& y, std::vector<double>& x, size_t n)
{
    uint64_t seed = 11;
    auto unit = [&] { // in [-1, 1)
        seed = seed * 6364136223846793005ull + 1442695040888963407ull;
        return double(seed >> 11) * 0x1p-52 - 1;
    };
    for (size_t i = 0; i < n; ++i) {
        const double a[3] = {unit(), unit(), unit()}, b[3] = {unit(), unit(), unit()};
        const double c[3] = {a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2],
                             a[0] * b[1] - a[1] * b[0]};
        double yi = std::sqrt(c[0] * c[0] + c[1] * c[1] + c[2] * c[2]),
               xi = a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
        if (i % 4 == 1) yi *= 1e-9;
        if (i % 4 == 2) xi *= 1e-9;
        if (i % 4 == 3)
            yi = std::abs(unit()) * std::pow(10, 20 * unit()), xi *= std::pow(10, 20 * unit());
        y.push_back(yi > 0 ? yi : 1e-300);
        x.push_back(xi);
    }
}

} // namespace

TEST(Angle, WithinTwoUlpOfAtan2OnRandomCorners)
{
    std::vector<double> y, x;
    corners(y, x, 200003); // not a multiple of 4: the last register is part full
    std::vector<int> widths = {2};
    if (util::doubleRegisterLanes() == 4) widths.push_back(4);
    std::vector<double> first;
    for (int lanes : widths) {
        std::vector<double> angle(y.size());
        util::angles(y.data(), x.data(), angle.data(), y.size(), lanes);
        size_t same = 0;
        for (size_t i = 0; i < y.size(); ++i) {
            const double expected = std::atan2(y[i], x[i]);
            ASSERT_LE(ulpsApart(angle[i], expected), 2)
                << lanes << " lanes: atan2(" << y[i] << ", " << x[i] << ") = " << expected
                << ", got " << angle[i];
            same += angle[i] == expected;
        }
        EXPECT_GT(same, y.size() / 2) << lanes << " lanes"; // most are atan2's double
        if (first.empty())
            first = angle;
        else
            EXPECT_EQ(angle, first) << "the same bits at 2 and 4 lanes";
    }
}

TEST(Angle, TheOctantsEdgesAreExact)
{
    const double y[] = {1, 1, 1, 1e-300, 3, 5e-324, 1, 2}, x[] = {0, 1, -1, -1, -3, 1, -0.0, 1e300};
    const size_t n = sizeof y / sizeof y[0];
    double angle[n];
    util::angles(y, x, angle, n);
    for (size_t i = 0; i < n; ++i)
        EXPECT_EQ(angle[i], std::atan2(y[i], x[i])) << y[i] << " " << x[i];
}

TEST(Angle, RegisterWidthsOtherThanTwoOrFourAreRefused)
{
    double y = 1, x = 1, a = 0;
    EXPECT_THROW(util::angles(&y, &x, &a, 1, 3), ValueError);
    EXPECT_THROW(util::angles(&y, &x, &a, 1, 8), ValueError);
    util::angles(&y, &x, &a, 0, 2); // nothing to do
    EXPECT_EQ(a, 0);
}
