// ParticleSet.cc - attribute lookup by name and by role, validation, non-finite filtering.
#include <fluidsurf/Error.h>
#include <fluidsurf/ParticleSet.h>

#include <tbb/blocked_range.h>
#include <tbb/parallel_reduce.h>

#include <algorithm>
#include <cstring>

namespace fluidsurf {

const char* Attribute::typeName() const
{
    static const char* kFloat[] = {"float", "float2", "float3", "float4"};
    static const char* kInt[] = {"int", "int2", "int3", "int4"};
    if (components >= 1 && components <= 4)
        return type == AttributeType::Float ? kFloat[components - 1] : kInt[components - 1];
    return type == AttributeType::Float ? "float[]" : "int[]";
}

const char* roleName(AttributeRole role)
{
    switch (role) {
    case AttributeRole::Radius:
        return "radius";
    case AttributeRole::Velocity:
        return "velocity";
    case AttributeRole::Density:
        return "density";
    case AttributeRole::Id:
        return "id";
    }
    return "?";
}

const Attribute* ParticleSet::find(const std::string& name) const
{
    for (const Attribute& a : attributes)
        if (a.name == name) return &a;
    return nullptr;
}

Attribute* ParticleSet::find(const std::string& name)
{
    for (Attribute& a : attributes)
        if (a.name == name) return &a;
    return nullptr;
}

namespace {
const char* const* aliasesOf(AttributeRole role)
{
    static const char* const kRadius[] = {"pscale", "radius", "Radius", nullptr};
    static const char* const kVelocity[] = {"v", "velocity", "vel", "Vel", "Velocity", nullptr};
    static const char* const kDensity[] = {"density", "rho", "Rhop", "Density", nullptr};
    static const char* const kId[] = {"id", "Idp", "index", "ID", "Id", nullptr};
    switch (role) {
    case AttributeRole::Radius:
        return kRadius;
    case AttributeRole::Velocity:
        return kVelocity;
    case AttributeRole::Density:
        return kDensity;
    case AttributeRole::Id:
        return kId;
    }
    return kRadius;
}
} // namespace

bool isRoleAlias(AttributeRole role, const std::string& name)
{
    for (const char* const* alias = aliasesOf(role); *alias; ++alias)
        if (name == *alias) return true;
    return false;
}

const Attribute* ParticleSet::find(AttributeRole role) const
{
    const int components = role == AttributeRole::Velocity ? 3 : 1;
    const bool mustBeFloat = role != AttributeRole::Id; // some writers store ids as floats
    for (const char* const* alias = aliasesOf(role); *alias; ++alias) {
        const Attribute* a = find(std::string(*alias));
        if (a && a->components == components && (!mustBeFloat || a->type == AttributeType::Float))
            return a;
    }
    return nullptr;
}

Attribute& ParticleSet::addFloat(const std::string& name, int components, std::vector<float> values)
{
    Attribute a;
    a.name = name;
    a.type = AttributeType::Float;
    a.components = components;
    a.floats = std::move(values);
    if (Attribute* old = find(name)) return *old = std::move(a);
    attributes.push_back(std::move(a));
    return attributes.back();
}

Attribute& ParticleSet::addInt(const std::string& name, int components, std::vector<int64_t> values)
{
    Attribute a;
    a.name = name;
    a.type = AttributeType::Int;
    a.components = components;
    a.ints = std::move(values);
    if (Attribute* old = find(name)) return *old = std::move(a);
    attributes.push_back(std::move(a));
    return attributes.back();
}

BBox3f boundsOf(const Vec3f* positions, size_t n)
{
    return tbb::parallel_reduce(
        tbb::blocked_range<size_t>(0, n, 1 << 16), BBox3f(),
        [&](const tbb::blocked_range<size_t>& r, BBox3f b) {
            for (size_t i = r.begin(); i != r.end(); ++i)
                b.expand(positions[i]);
            return b;
        },
        [](BBox3f a, const BBox3f& b) {
            for (int k = 0; k < 3; ++k)
                a.min[k] = std::min(a.min[k], b.min[k]), a.max[k] = std::max(a.max[k], b.max[k]);
            return a;
        });
}

BBox3f ParticleSet::bbox() const
{
    return boundsOf(positions.data(), positions.size());
}

void ParticleSet::validate() const
{
    for (const Attribute& a : attributes) {
        if (a.components < 1) throw ValueError("attribute '" + a.name + "' has no components");
        if (a.size() != size() * size_t(a.components))
            throw ValueError("attribute '" + a.name + "' holds " + std::to_string(a.size()) +
                             " values, expected " + std::to_string(size() * a.components));
    }
}

namespace {
template <typename T>
void compact(std::vector<T>& values, const std::vector<char>& keep, int components)
{
    size_t out = 0;
    for (size_t i = 0; i < keep.size(); ++i) {
        if (!keep[i]) continue;
        if (out != i)
            std::memmove(&values[out * components], &values[i * components],
                         sizeof(T) * components);
        ++out;
    }
    values.resize(out * components);
}
} // namespace

size_t ParticleSet::dropNonFinite()
{
    std::vector<char> keep(size());
    size_t dropped = 0;
    for (size_t i = 0; i < size(); ++i) {
        keep[i] = positions[i].isWithinRange(); // (past kMaxCoordinate no distance is finite)
        dropped += !keep[i];
    }
    if (dropped == 0) return 0;
    compact(positions, keep, 1);
    for (Attribute& a : attributes) {
        if (a.type == AttributeType::Float)
            compact(a.floats, keep, a.components);
        else
            compact(a.ints, keep, a.components);
    }
    return dropped;
}

} // namespace fluidsurf
