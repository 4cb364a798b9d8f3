// VdbPointsIO.cc - OpenVDB points (.vdb PointDataGrid with a "P" attribute), read and write.
//
// Bit-exact positions: VDB stores a point as its voxel plus a float offset inside the voxel.
// With a power-of-two voxel size and no translation, index-space coordinates are exact scalings
// of the float32 world coordinates, the offset keeps all 24 mantissa bits, and converting back
// in double reproduces the original float exactly. Point order is not part of a VDB (points
// are bucketed by voxel), so a round trip keeps each particle, not their order.
#include "io/Formats.h"
#include "io/VdbGrids.h"
#include "io/VdbWrite.h"

#include <fluidsurf/Error.h>

#include <openvdb/openvdb.h>
#include <openvdb/points/PointConversion.h>
#include <openvdb/points/PointDataGrid.h>

#include <cmath>

namespace fluidsurf {
namespace io_internal {

namespace {

template <typename T>
void copyValues(const openvdb::points::AttributeArray& array, openvdb::Index idx, int stride,
                T* out)
{
    openvdb::points::AttributeHandle<T> h(array);
    for (int c = 0; c < stride; ++c)
        out[c] = h.get(idx, openvdb::Index(c));
}

std::string originText(const openvdb::Coord& c)
{
    return "(" + std::to_string(c.x()) + ", " + std::to_string(c.y()) + ", " +
           std::to_string(c.z()) + ")";
}

/// What the loop below trusts of each leaf, checked first: OpenVDB reads the voxel offsets and
/// the attribute arrays of a leaf without comparing them, and indexes the arrays with the
/// offsets (an assertion, or a read past the array, on a corrupt file).
void checkPointLeaves(const openvdb::points::PointDataGrid& grid,
                      const openvdb::points::AttributeSet::Descriptor& desc, const std::string& src)
{
    const std::string where = src + ": corrupt VDB points (grid '" + grid.getName() + "'): ";
    auto first = grid.tree().cbeginLeaf();
    for (auto leaf = grid.tree().cbeginLeaf(); leaf; ++leaf) {
        const openvdb::points::AttributeSet& set = leaf->attributeSet();
        if (set.descriptor().map() != desc.map())
            throw InputError(src + ": leaves of grid '" + grid.getName() +
                             "' carry different attributes");
        openvdb::Index end = 0;
        for (openvdb::Index v = 0; v < leaf->SIZE; ++v) {
            if (leaf->getValue(v) < end)
                throw InputError(where + "voxel point offsets decrease in leaf at " +
                                 originText(leaf->origin()));
            end = leaf->getValue(v);
        }
        for (size_t a = 0; a < set.size(); ++a) {
            const openvdb::points::AttributeArray* array = set.getConst(a);
            const openvdb::points::AttributeArray* model = first->attributeSet().getConst(a);
            if (!array || !model || !array->hasConstantStride() ||
                array->stride() != model->stride() || array->type() != model->type() ||
                (!array->isUniform() && array->size() < end))
                throw InputError(where + "attribute arrays do not match the leaf's " +
                                 std::to_string(end) + " points in leaf at " +
                                 originText(leaf->origin()));
        }
    }
}

} // namespace

ParticleSet readVdbPoints(const uint8_t* data, size_t size, const std::string& src,
                          std::string* detail)
{
    const openvdb::GridPtrVecPtr grids = readVdbGrids(data, size, src);
    openvdb::points::PointDataGrid::Ptr grid;
    std::string names;
    for (auto& g : *grids) {
        names += (names.empty() ? "" : ", ") + g->getName() + " (" + g->valueType() + ")";
        auto pg = openvdb::gridPtrCast<openvdb::points::PointDataGrid>(g);
        if (!pg || grid) continue;
        auto leaf = pg->tree().cbeginLeaf();
        if (!leaf || leaf->attributeSet().find("P") != openvdb::points::AttributeSet::INVALID_POS)
            grid = pg;
    }
    if (!grid)
        throw InputError(src + ": no PointDataGrid with a \"P\" attribute in this VDB (grids: " +
                         (names.empty() ? std::string("none") : names) + ")");

    ParticleSet set;
    const openvdb::math::Transform& xform = grid->transform();
    auto first = grid->tree().cbeginLeaf();
    if (!first) {
        if (detail) *detail = "grid '" + grid->getName() + "', empty";
        return set;
    }
    // Attribute layout from the first leaf's descriptor (shared by all leaves).
    struct Column
    {
        std::string name;
        size_t pos;
        int stride;
        enum { F, F3, D, D3, I32, I64, I3 } kind;
    };
    std::vector<Column> columns;
    std::string skipped;
    const auto& desc = first->attributeSet().descriptor();
    for (const auto& [name, pos] : desc.map()) {
        if (name == "P") continue;
        const auto& type = desc.type(pos).first;
        const int stride = int(first->constAttributeArray(pos).stride());
        Column c{name, pos, stride, Column::F};
        if (type == "float")
            c.kind = Column::F;
        else if (type == "vec3s")
            c.kind = Column::F3;
        else if (type == "double")
            c.kind = Column::D;
        else if (type == "vec3d")
            c.kind = Column::D3;
        else if (type == "int32")
            c.kind = Column::I32;
        else if (type == "int64")
            c.kind = Column::I64;
        else if (type == "vec3i")
            c.kind = Column::I3;
        else {
            skipped += (skipped.empty() ? "" : ", ") + name + " (" + type + ")";
            continue;
        }
        columns.push_back(c);
    }
    const size_t posIndex = desc.find("P");
    const auto pType = desc.type(posIndex).first;
    if (pType != "vec3s") throw InputError(src + ": \"P\" has type " + pType + ", vec3s expected");
    std::vector<std::vector<float>> fcols(columns.size());
    std::vector<std::vector<int64_t>> icols(columns.size());
    auto isFloat = [](const Column& c) { return c.kind <= Column::D3; };
    auto comps = [](const Column& c) {
        return (c.kind == Column::F3 || c.kind == Column::D3 || c.kind == Column::I3) ? 3 * c.stride
                                                                                      : c.stride;
    };

    checkPointLeaves(*grid, desc, src);
    for (auto leaf = grid->tree().cbeginLeaf(); leaf; ++leaf) {
        openvdb::points::AttributeHandle<openvdb::Vec3f> ph(leaf->constAttributeArray(posIndex));
        for (auto idx = leaf->beginIndexAll(); idx; ++idx) {
            const openvdb::Vec3d voxel = idx.getCoord().asVec3d();
            const openvdb::Vec3d w = xform.indexToWorld(voxel + openvdb::Vec3d(ph.get(*idx)));
            set.positions.emplace_back(float(w.x()), float(w.y()), float(w.z()));
            for (size_t k = 0; k < columns.size(); ++k) {
                const Column& c = columns[k];
                const auto& array = leaf->constAttributeArray(c.pos);
                const int n = comps(c);
                if (isFloat(c)) {
                    fcols[k].resize(fcols[k].size() + n);
                    float* o = &fcols[k][fcols[k].size() - n];
                    if (c.kind == Column::F)
                        copyValues<float>(array, *idx, c.stride, o);
                    else if (c.kind == Column::D) {
                        std::vector<double> t(n);
                        copyValues<double>(array, *idx, c.stride, t.data());
                        for (int j = 0; j < n; ++j)
                            o[j] = float(t[j]);
                    } else if (c.kind == Column::F3) {
                        std::vector<openvdb::Vec3f> t(c.stride);
                        copyValues<openvdb::Vec3f>(array, *idx, c.stride, t.data());
                        for (int j = 0; j < n; ++j)
                            o[j] = t[j / 3][j % 3];
                    } else {
                        std::vector<openvdb::Vec3d> t(c.stride);
                        copyValues<openvdb::Vec3d>(array, *idx, c.stride, t.data());
                        for (int j = 0; j < n; ++j)
                            o[j] = float(t[j / 3][j % 3]);
                    }
                } else {
                    icols[k].resize(icols[k].size() + n);
                    int64_t* o = &icols[k][icols[k].size() - n];
                    if (c.kind == Column::I64)
                        copyValues<int64_t>(array, *idx, c.stride, o);
                    else if (c.kind == Column::I32) {
                        std::vector<int32_t> t(n);
                        copyValues<int32_t>(array, *idx, c.stride, t.data());
                        for (int j = 0; j < n; ++j)
                            o[j] = t[j];
                    } else {
                        std::vector<openvdb::Vec3i> t(c.stride);
                        copyValues<openvdb::Vec3i>(array, *idx, c.stride, t.data());
                        for (int j = 0; j < n; ++j)
                            o[j] = t[j / 3][j % 3];
                    }
                }
            }
        }
    }
    for (size_t k = 0; k < columns.size(); ++k) {
        if (isFloat(columns[k]))
            set.addFloat(columns[k].name, comps(columns[k]), std::move(fcols[k]));
        else
            set.addInt(columns[k].name, comps(columns[k]), std::move(icols[k]));
    }
    if (detail) {
        *detail = "grid '" + grid->getName() + "', voxel " + std::to_string(xform.voxelSize()[0]);
        if (!skipped.empty()) *detail += ", skipped attributes: " + skipped;
    }
    return set;
}

void writeVdbPoints(const ParticleSet& ps, const std::string& path, bool compress)
{
    namespace vdb = openvdb;
    namespace points = openvdb::points;
    using VdbVec3f = openvdb::Vec3f;
    ps.validate();
    size_t bad = 0;
    for (const Vec3f& p : ps.positions)
        bad += !p.isFinite();
    if (bad)
        throw OutputError(path + ": " + std::to_string(bad) +
                          " particle(s) have NaN/Inf positions, which VDB points cannot store");
    vdb::initialize();
    std::vector<VdbVec3f> positions;
    positions.reserve(ps.size());
    for (const Vec3f& p : ps.positions)
        positions.emplace_back(p.x, p.y, p.z);
    points::PointAttributeVector<VdbVec3f> wrapper(positions);
    // About 8 points per voxel, rounded down to a power of two (see the header comment).
    double voxel = ps.size() > 1 ? double(points::computeVoxelSize(wrapper, 8)) : 1.0;
    if (!(voxel > 0) || !std::isfinite(voxel)) voxel = 1.0;
    voxel = std::ldexp(1.0, int(std::floor(std::log2(voxel))));
    // Keep index coordinates inside VDB's int32 range.
    const BBox3f box = ps.bbox();
    for (int a = 0; a < 3 && !box.empty(); ++a)
        while (std::max(std::fabs(box.min[a]), std::fabs(box.max[a])) / voxel > 1e9)
            voxel *= 2;
    auto xform = vdb::math::Transform::createLinearTransform(voxel);
    auto indexGrid = vdb::tools::createPointIndexGrid<vdb::tools::PointIndexGrid>(wrapper, *xform);
    auto grid = points::createPointDataGrid<points::NullCodec, points::PointDataGrid>(
        *indexGrid, wrapper, *xform);
    for (const Attribute& a : ps.attributes) {
        if (a.name == "P")
            throw OutputError(path + ": attribute named \"P\" clashes with VDB positions");
        if (a.type == AttributeType::Float && a.components == 3) {
            std::vector<VdbVec3f> v(ps.size());
            for (size_t i = 0; i < v.size(); ++i)
                v[i] = VdbVec3f(&a.floats[3 * i]);
            points::appendAttribute<VdbVec3f>(grid->tree(), a.name);
            points::populateAttribute(grid->tree(), indexGrid->tree(), a.name,
                                      points::PointAttributeVector<VdbVec3f>(v));
        } else if (a.type == AttributeType::Float) {
            points::appendAttribute<float>(grid->tree(), a.name, 0.f, vdb::Index(a.components));
            points::populateAttribute(
                grid->tree(), indexGrid->tree(), a.name,
                points::PointAttributeVector<float>(a.floats, vdb::Index(a.components)),
                vdb::Index(a.components));
        } else {
            points::appendAttribute<int64_t>(grid->tree(), a.name, int64_t(0),
                                             vdb::Index(a.components));
            points::populateAttribute(
                grid->tree(), indexGrid->tree(), a.name,
                points::PointAttributeVector<int64_t>(a.ints, vdb::Index(a.components)),
                vdb::Index(a.components));
        }
    }
    grid->setName("points");
    grid->insertMeta("fluidsurf_particle_count", vdb::Int64Metadata(int64_t(ps.size())));
    io_internal::writeVdbFile({grid}, path,
                              compress ? openvdb::io::COMPRESS_BLOSC : openvdb::io::COMPRESS_NONE,
                              /*uuidFromContent=*/false);
}

} // namespace io_internal
} // namespace fluidsurf
