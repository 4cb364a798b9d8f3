// Objects.cc - Mesh and LevelSet, and the calls that take or give one.
#include "Objects.h"

#include "Arrays.h"
#include "Kwargs.h"

#include <fluidsurf/MeshCheck.h>
#include <fluidsurf/MeshLevelSet.h>
#include <fluidsurf/PostProcess.h>
#include <fluidsurf/io/LevelSetIO.h>
#include <fluidsurf/io/MeshIO.h>

#include <openvdb/tools/Interpolation.h>
#include <pybind11/numpy.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

namespace py = pybind11;

namespace fluidsurf {
namespace python {

namespace {

py::dict reportDict(const MeshReport& r)
{
    py::dict d;
    d["vertices"] = r.vertices, d["triangles"] = r.triangles;
    d["unused_vertices"] = r.unusedVertices, d["boundary_edges"] = r.boundaryEdges;
    d["non_manifold_edges"] = r.nonManifoldEdges;
    d["non_manifold_vertices"] = r.nonManifoldVertices;
    d["misoriented_edges"] = r.misorientedEdges;
    d["degenerate_triangles"] = r.degenerateTriangles, d["components"] = r.components;
    d["thin_triangles"] = r.thinTriangles, d["min_angle_degrees"] = r.minAngleDegrees;
    d["volume"] = r.volume, d["area"] = r.area, d["watertight"] = r.watertight();
    return d;
}

void bindMesh(py::module_& m)
{
    py::class_<PyMesh>(m, "Mesh",
                       "An indexed triangle mesh: vertices (V, 3) float32, triangles (T, 3) uint32 "
                       "counter-clockwise seen from outside, normals (V, 3) float32 or None. The "
                       "arrays are views of the mesh's own memory (writable, no copy); info holds "
                       "what the call that made it learned.")
        .def(py::init([](py::handle vertices, py::handle triangles, py::handle normals,
                         py::handle attributes) {
                 PyMesh me{meshFrom(vertices, triangles, normals), py::dict(), {}};
                 me.attributes = attributesFrom(attributes, me.mesh.points.size());
                 return me;
             }),
             py::arg("vertices"), py::arg("triangles"), py::arg("normals") = py::none(),
             py::arg("attributes") = py::none())
        .def_property_readonly(
            "vertices",
            [](py::object self) { return view(self.cast<PyMesh&>().mesh.points, self); })
        .def_property_readonly(
            "triangles",
            [](py::object self) { return view(self.cast<PyMesh&>().mesh.triangles, self); })
        .def_property_readonly("normals",
                               [](py::object self) -> py::object {
                                   PyMesh& me = self.cast<PyMesh&>();
                                   if (me.mesh.normals.empty()) return py::none();
                                   return view(me.mesh.normals, self);
                               })
        .def_readonly("info", &PyMesh::info)
        .def_property_readonly(
            "attributes",
            [](const PyMesh& me) { return attributesToDict(me.attributes, me.mesh.points.size()); },
            "{name: (V,) or (V, k) array} of vertex attributes (copies), e.g. the particles' "
            "velocity carried onto the vertices by reconstruct(..., attributes=...).")
        .def(
            "check",
            [](const PyMesh& me) {
                MeshReport r;
                {
                    py::gil_scoped_release noGil;
                    r = checkMesh(me.mesh);
                }
                return reportDict(r);
            },
            "Boundary and non-manifold edges, orientation, components, volume, ... as a dict "
            "('watertight': closed, manifold, oriented, no degenerate triangle).")
        .def(
            "write",
            [](const PyMesh& me, const std::string& path) {
                const bool obj = io::meshFormatFromPath(path) == io::MeshFormat::Obj;
                if (obj && !me.attributes.empty())
                    PyErr_WarnEx(PyExc_UserWarning,
                                 ("OBJ cannot hold vertex attributes: they are not written to " +
                                  path + " (write .ply or .vtk)")
                                     .c_str(),
                                 1);
                py::gil_scoped_release noGil;
                io::writeMesh(me.mesh, path, obj ? std::vector<Attribute>() : me.attributes);
            },
            py::arg("path"),
            "Write .obj, .ply (binary) or .vtk, atomically; vertex attributes as PLY properties "
            "(v as vx vy vz) or VTK point data (OBJ cannot hold them: a warning says so).")
        .def("__repr__", [](const PyMesh& me) {
            return "<fluidsurf.Mesh " + std::to_string(me.mesh.points.size()) + " vertices, " +
                   std::to_string(me.mesh.triangles.size()) + " triangles>";
        });

    m.def(
        "read_mesh",
        [](const std::string& path) {
            return PyMesh{io::readMesh(path), py::dict(), {}};
        },
        py::arg("path"), "Read an .obj or .ply mesh (polygons fanned into triangles).");

    m.def(
        "post_process",
        [](const PyMesh& in, double voxelSize, const py::kwargs& kwargs) {
            Settings s = settingsFrom(kwargs, kPost | kRun);
            s.params.post.voxelSize = voxelSize;
            if (!in.attributes.empty())
                PyErr_WarnEx(PyExc_UserWarning,
                             "post_process does not carry vertex attributes: pass the particles' "
                             "attributes to reconstruct, which evaluates them at the final "
                             "vertices",
                             1);
            Context ctx;
            setUp(ctx, s);
            PostProcessStats stats;
            PyMesh out;
            out.mesh = compute(s, ctx, [&] {
                validate(s.params.post);
                return postProcessMesh(in.mesh, s.params.post, ctx, &stats);
            });
            out.info["input_triangles"] = stats.inputTriangles;
            out.info["decimated_triangles"] = stats.decimatedTriangles;
            out.info["timing"] = ctx.timing().format();
            return out;
        },
        py::arg("mesh"), py::arg("voxel_size") = 0.0,
        ("Decimation, smoothing and Loop subdivision of any mesh, as `fluidsurf post`. "
         "voxel_size: the voxel the bounds count in (0: the mean edge length). Parameters: " +
         describeParams(kPost | kRun))
            .c_str());
}

/// Trilinear samples of grid at world points, in parallel (one accessor per range).
py::array_t<float> sample(const openvdb::FloatGrid& grid, const std::vector<Vec3f>& points)
{
    py::array_t<float> out(py::ssize_t(points.size()));
    float* values = out.mutable_data();
    py::gil_scoped_release noGil;
    tbb::parallel_for(tbb::blocked_range<size_t>(0, points.size(), 1024),
                      [&](const tbb::blocked_range<size_t>& range) {
                          openvdb::tools::GridSampler<openvdb::FloatGrid::ConstAccessor,
                                                      openvdb::tools::BoxSampler>
                              sampler(grid.getConstAccessor(), grid.transform());
                          for (size_t i = range.begin(); i != range.end(); ++i) {
                              const Vec3f& p = points[i];
                              values[i] = sampler.wsSample(openvdb::Vec3d(p.x, p.y, p.z));
                          }
                      });
    return out;
}

/// Every grid a LevelSet writes: the level set (or the adaptive grid's three), then attributes.
openvdb::GridPtrVec allGrids(const PyLevelSet& ls)
{
    openvdb::GridPtrVec grids =
        ls.adaptive.empty() ? openvdb::GridPtrVec{ls.grid} : ls.adaptive.grids();
    grids.insert(grids.end(), ls.attributeGrids.begin(), ls.attributeGrids.end());
    return grids;
}

void bindLevelSet(py::module_& m)
{
    py::class_<PyLevelSet>(m, "LevelSet",
                           "A narrow-band level set (OpenVDB FloatGrid 'surface', negative "
                           "inside), or with adaptive=True the three grids of the adaptive grid "
                           "(then sample and voxel_size are those of 'surface', its level 2).")
        .def_property_readonly("voxel_size",
                               [](const PyLevelSet& ls) { return ls.grid->voxelSize()[0]; })
        .def_property_readonly("background",
                               [](const PyLevelSet& ls) { return ls.grid->background(); })
        .def_property_readonly("active_voxels",
                               [](const PyLevelSet& ls) { return ls.grid->activeVoxelCount(); })
        .def_property_readonly("adaptive",
                               [](const PyLevelSet& ls) { return !ls.adaptive.empty(); })
        .def_property_readonly("grid_names",
                               [](const PyLevelSet& ls) {
                                   py::list names;
                                   for (const auto& g : allGrids(ls))
                                       names.append(g->getName());
                                   return names;
                               })
        .def_readonly("info", &PyLevelSet::info)
        .def(
            "sample",
            [](const PyLevelSet& ls, py::handle points) {
                return sample(*ls.grid, pointsFrom(points, "points"));
            },
            py::arg("points"),
            "The level set at world points (M, 3), trilinear; the background (with its sign) "
            "outside the band.")
        .def(
            "write",
            [](const PyLevelSet& ls, const std::string& path) {
                py::gil_scoped_release noGil;
                io::writeLevelSet(allGrids(ls), path);
            },
            py::arg("path"),
            "Write a .vdb (Blosc), atomically, with the attribute grids; any VDB tool opens it.")
        .def(
            "mesh",
            [](const PyLevelSet& ls, const py::kwargs& kwargs) {
                const Settings s = settingsFrom(kwargs, kMesh | kRun);
                if (!ls.adaptive.empty() && s.params.mesh.mesher != Mesher::MarchingCubes)
                    throw ValueError("an adaptive grid is meshed by its own mesher only "
                                     "(mesher='mc')");
                Context ctx;
                setUp(ctx, s);
                PyMesh out;
                out.mesh = compute(s, ctx, [&] {
                    return ls.adaptive.empty() ? meshLevelSet(*ls.grid, s.params.mesh.mesher, ctx)
                                               : meshAdaptiveGrid(ls.adaptive, ctx);
                });
                out.info["timing"] = ctx.timing().format();
                return out;
            },
            ("The zero crossing as a mesh, without post-processing (as `fluidsurf mesh --raw`). "
             "Parameters: " +
             describeParams(kMesh | kRun))
                .c_str())
        .def(
            "to_pyopenvdb",
            [](const PyLevelSet& ls) {
                // pyopenvdb's grids are its own C++ objects: hand them over through a file
                py::module_ vdb = py::module_::import("pyopenvdb");
                py::module_ tempfile = py::module_::import("tempfile");
                py::object dir = tempfile.attr("TemporaryDirectory")();
                const std::string path = std::string(py::str(dir.attr("name"))) + "/grids.vdb";
                try {
                    {
                        py::gil_scoped_release noGil;
                        io::writeLevelSet(allGrids(ls), path);
                    }
                    py::list out;
                    for (const auto& g : allGrids(ls)) // pyopenvdb reads float and vec3s only
                        // (not isType<>: see CMakeLists.txt)
                        if (g->valueType() == "float" || g->valueType() == "vec3s")
                            out.append(vdb.attr("read")(path, g->getName()));
                    dir.attr("cleanup")();
                    return out.size() == 1 ? py::object(out[0]) : py::object(out);
                } catch (...) {
                    dir.attr("cleanup")();
                    throw;
                }
            },
            "The grid(s) as pyopenvdb objects (Debian's python3-openvdb): one grid, or a list "
            "(the adaptive grid's, attribute grids; integer grids are left out: pyopenvdb "
            "cannot hold them).")
        .def("__repr__", [](const PyLevelSet& ls) {
            return "<fluidsurf.LevelSet " + std::string(ls.adaptive.empty() ? "" : "adaptive, ") +
                   "voxel " + std::to_string(ls.grid->voxelSize()[0]) + ", " +
                   std::to_string(ls.grid->activeVoxelCount()) + " active voxels>";
        });

    m.def(
        "read_level_set",
        [](const std::string& path, const std::string& grid) {
            io::LevelSetFile f = io::readLevelSetFile(path, grid);
            return PyLevelSet{f.grid, f.adaptive, py::dict(), {}};
        },
        py::arg("path"), py::arg("grid") = "",
        "Read a level set from a .vdb: the grid named grid, else the adaptive grid when the file "
        "holds one, else the first level set.");
}

} // namespace

void bindObjects(py::module_& m)
{
    bindMesh(m);
    bindLevelSet(m);
}

} // namespace python
} // namespace fluidsurf
