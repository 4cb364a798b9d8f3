// Vec3.h - a plain 3-float vector. Kept independent of OpenVDB so that headers stay light
// (OpenVDB headers dominate compile times) and the layout matches CUDA's float3.
#pragma once

#include <cmath>

namespace fluidsurf {

/// The largest coordinate (and length) the pipeline accepts, in world units: squared distances
/// and sums of them stay far inside float32's range (3.4e38) for any two points within it. Past
/// it, distances overflow to inf and a frame came out as isolated spheres, an empty mesh or NaN
/// vertices; such input is refused with this bound in the message.
constexpr double kMaxCoordinate = 1e15;

struct Vec3f
{
    float x = 0.f, y = 0.f, z = 0.f;

    Vec3f() = default;
    constexpr Vec3f(float x_, float y_, float z_) : x(x_), y(y_), z(z_) {}

    float& operator[](int i) { return i == 0 ? x : (i == 1 ? y : z); }
    float operator[](int i) const { return i == 0 ? x : (i == 1 ? y : z); }

    Vec3f operator+(const Vec3f& o) const { return {x + o.x, y + o.y, z + o.z}; }
    Vec3f operator-(const Vec3f& o) const { return {x - o.x, y - o.y, z - o.z}; }
    Vec3f operator*(float s) const { return {x * s, y * s, z * s}; }
    bool operator==(const Vec3f& o) const { return x == o.x && y == o.y && z == o.z; }
    bool operator!=(const Vec3f& o) const { return !(*this == o); }

    bool isFinite() const { return std::isfinite(x) && std::isfinite(y) && std::isfinite(z); }
    /// Finite and within +-kMaxCoordinate on every axis (NaN fails too).
    bool isWithinRange() const
    {
        const float m = float(kMaxCoordinate);
        return std::fabs(x) <= m && std::fabs(y) <= m && std::fabs(z) <= m;
    }
};

static_assert(sizeof(Vec3f) == 12, "Vec3f must be three packed floats");

/// Axis-aligned bounding box; empty when min > max.
struct BBox3f
{
    Vec3f min{INFINITY, INFINITY, INFINITY};
    Vec3f max{-INFINITY, -INFINITY, -INFINITY};

    bool empty() const { return min.x > max.x; }
    void expand(const Vec3f& p)
    {
        for (int a = 0; a < 3; ++a) {
            if (p[a] < min[a]) min[a] = p[a];
            if (p[a] > max[a]) max[a] = p[a];
        }
    }
};

} // namespace fluidsurf
