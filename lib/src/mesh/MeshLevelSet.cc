// MeshLevelSet.cc - mesher choice, and reading a level set from a .vdb file.
#include <fluidsurf/Error.h>
#include <fluidsurf/MeshLevelSet.h>

#include "io/FileBuffer.h"
#include "io/VdbGrids.h"
#include "mesh/MarchingCubes.h"
#include "mesh/VolumeToMesh.h"

#include <chrono>

namespace fluidsurf {

const char* mesherName(Mesher m)
{
    return m == Mesher::MarchingCubes ? "mc" : "openvdb";
}

Mesher mesherFromName(const std::string& name)
{
    if (name == "mc") return Mesher::MarchingCubes;
    if (name == "openvdb") return Mesher::OpenVdb;
    throw ValueError("unknown mesher '" + name + "' (mc, openvdb)");
}

TriangleMesh meshLevelSet(const openvdb::FloatGrid& grid, Mesher mesher, MeshStats* stats)
{
    if (!grid.transform().isLinear())
        throw ValueError("grid '" + grid.getName() +
                         "' has a non-linear (frustum) transform; only linear ones are meshed");
    const auto start = std::chrono::steady_clock::now();
    size_t cells = 0;
    TriangleMesh m = mesher == Mesher::MarchingCubes ? mesh::marchingCubes(grid, &cells)
                                                     : mesh::openvdbVolumeToMesh(grid);
    if (stats) {
        stats->surfaceCells = cells;
        stats->vertices = m.points.size();
        stats->triangles = m.triangles.size();
        stats->seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    }
    return m;
}

openvdb::FloatGrid::Ptr readLevelSet(const std::string& path, const std::string& gridName)
{
    const std::vector<uint8_t> bytes = io_internal::readFile(path);
    const openvdb::GridPtrVecPtr grids =
        io_internal::readVdbGrids(bytes.data(), bytes.size(), path);
    openvdb::FloatGrid::Ptr levelSet, anyFloat;
    std::string names;
    for (const openvdb::GridBase::Ptr& g : *grids) {
        names += (names.empty() ? "" : ", ") + g->getName() + " (" + g->valueType() + ", " +
                 openvdb::GridBase::gridClassToString(g->getGridClass()) + ")";
        auto f = openvdb::gridPtrCast<openvdb::FloatGrid>(g);
        if (!f) continue;
        if (!gridName.empty()) {
            if (f->getName() == gridName && !levelSet) levelSet = f;
            continue;
        }
        if (!levelSet && f->getGridClass() == openvdb::GRID_LEVEL_SET) levelSet = f;
        if (!anyFloat) anyFloat = f;
    }
    if (!levelSet) levelSet = gridName.empty() ? anyFloat : nullptr;
    if (!levelSet)
        throw InputError(
            path + ": no " +
            (gridName.empty() ? std::string("float grid") : "float grid named '" + gridName + "'") +
            " in this VDB (grids: " + (names.empty() ? std::string("none") : names) + ")");
    return levelSet;
}

} // namespace fluidsurf
