// Objects.h - the two result types of the Python package: Mesh (vertices, triangles, normals as
// NumPy views of the C++ arrays, no copy; vertex attributes) and LevelSet (an OpenVDB level set, or
// the three grids of the adaptive grid). Each carries `info`, a dict of what the call that made it
// learned (radius and its source, isolated particles, counts, the timing tree).
#pragma once

#include <fluidsurf/AdaptiveGrid.h>
#include <fluidsurf/Mesh.h>
#include <fluidsurf/ParticleSet.h>

#include <openvdb/openvdb.h>
#include <pybind11/pybind11.h>

namespace fluidsurf {
namespace python {

struct PyMesh
{
    TriangleMesh mesh;
    pybind11::dict info;
    std::vector<Attribute> attributes; ///< one value (or k) per vertex
};

struct PyLevelSet
{
    openvdb::FloatGrid::Ptr grid; ///< with an adaptive grid, its level 2 ("surface")
    AdaptiveGrid adaptive;
    pybind11::dict info;
    openvdb::GridPtrVec attributeGrids; ///< particle attributes over the band ("v", ...)
};

/// Adds the classes Mesh and LevelSet (and read_mesh, read_level_set, post_process) to m.
void bindObjects(pybind11::module_& m);

} // namespace python
} // namespace fluidsurf
