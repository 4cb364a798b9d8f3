// ParticleSet.h - one frame of particles in memory: float32 positions plus named per-particle
// attributes (structure of arrays). Readers fill it, every pipeline stage reads it.
//
// Well-known attributes are found by role through common aliases, so names from any simulator
// survive a round trip unchanged: radius ("pscale", "radius"), velocity ("v", "velocity",
// "vel", "Vel"), density ("density", "rho", "Rhop"), id ("id", "Idp", "index").
#pragma once

#include <fluidsurf/Vec3.h>

#include <cstdint>
#include <string>
#include <vector>

namespace fluidsurf {

enum class AttributeType { Float, Int };

/// One named per-particle attribute with 1..16 components, stored interleaved
/// (particle i, component c at [i * components + c]). Floats are float32; integers int64, so
/// 64-bit ids from VTK XML survive; formats with 32-bit ints check the range when writing.
struct Attribute
{
    std::string name;
    AttributeType type = AttributeType::Float;
    int components = 1;
    std::vector<float> floats; ///< used when type == Float
    std::vector<int64_t> ints; ///< used when type == Int

    size_t size() const { return type == AttributeType::Float ? floats.size() : ints.size(); }
    const char* typeName() const; ///< "float", "float3", "int", ...
};

enum class AttributeRole { Radius, Velocity, Density, Id };

class ParticleSet
{
public:
    std::vector<Vec3f> positions;
    std::vector<Attribute> attributes;

    size_t size() const { return positions.size(); }
    bool empty() const { return positions.empty(); }

    /// Attribute by exact name, or nullptr.
    const Attribute* find(const std::string& name) const;
    Attribute* find(const std::string& name);
    /// Attribute playing a role (by alias and shape: a radius is a 1-component float), or nullptr.
    const Attribute* find(AttributeRole role) const;

    /// Add (or replace) an attribute; its size must be components * size().
    Attribute& addFloat(const std::string& name, int components, std::vector<float> values);
    Attribute& addInt(const std::string& name, int components, std::vector<int64_t> values);

    BBox3f bbox() const; ///< boundsOf(positions)

    /// Throws ValueError when an attribute's length does not match the particle count.
    void validate() const;

    /// Remove particles whose position is not finite (NaN/Inf) or lies past kMaxCoordinate,
    /// together with their attribute values; returns how many were removed.
    size_t dropNonFinite();
};

const char* roleName(AttributeRole role);
/// Whether name is one of the aliases by which ParticleSet::find(role) looks ("Rhop": density).
bool isRoleAlias(AttributeRole role, const std::string& name);

/// The bounds of n points, on all threads (exact: min and max in any order); empty for none.
BBox3f boundsOf(const Vec3f* positions, size_t n);

} // namespace fluidsurf
