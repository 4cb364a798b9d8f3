// Module.cc - the Python package `fluidsurf`: a thin layer over Reconstruct.h (DESIGN.md, front
// ends). Arrays in, arrays out; parameters named and defaulted as the CLI's options (Kwargs.h);
// the GIL released while the library computes; the library's exceptions as Python ones with the
// same messages:
//   fluidsurf.Error (RuntimeError) <- InputError, OutputError (also OSError), Cancelled
//   fluidsurf.ValueError (also Python's ValueError)
//
//   import numpy as np, fluidsurf
//   mesh = fluidsurf.reconstruct(positions, radius=0.025)      # positions: (N, 3) array
//   mesh.vertices, mesh.triangles, mesh.normals, mesh.info["radius"], mesh.write("f.ply")
//   ls = fluidsurf.rasterize(positions, radius=0.025); ls.sample(points); ls.write("f.vdb")
#include "Arrays.h"
#include "Kwargs.h"
#include "Objects.h"

#include <fluidsurf/Error.h>
#include <fluidsurf/Reconstruct.h>
#include <fluidsurf/Scenes.h>
#include <fluidsurf/TransferAttributes.h>
#include <fluidsurf/Version.h>
#include <fluidsurf/io/ParticleIO.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <cmath>
#include <cstring>

namespace py = pybind11;

namespace fluidsurf {
namespace python {

namespace {

double checkedRadius(double radius)
{
    if (!std::isfinite(radius) || radius < 0)
        throw ValueError("radius must be a positive finite number, or 0 to choose it from the "
                         "particles (got " +
                         std::to_string(radius) + ")");
    return radius;
}

py::array_t<uint32_t> indices(const std::vector<uint32_t>& v)
{
    py::array_t<uint32_t> a(py::ssize_t(v.size()));
    if (!v.empty()) std::memcpy(a.mutable_data(), v.data(), v.size() * sizeof(uint32_t));
    return a;
}

void addFieldInfo(py::dict& info, const RadiusChoice& radius, const RasterizeStats& s,
                  const std::vector<uint32_t>& isolated)
{
    info["radius"] = radius.radius;
    info["radius_source"] = radiusSourceName(radius.source);
    info["radius_detail"] = radius.detail;
    info["device"] = s.device;
    info["particles"] = s.particles, info["interior"] = s.interior;
    info["surface"] = s.surface, info["splash"] = s.splash, info["isolated"] = s.isolated;
    info["active_voxels"] = s.activeVoxels;
    info["isolated_particles"] = indices(isolated);
}

const char* kParticlesDoc =
    "positions: (N, 3) float32 or float64 array of finite coordinates. radius: the particle "
    "radius r (half the rest spacing), world units; 0 chooses it from radii, else estimates it "
    "(info['radius_source'] says which). radii: optional (N,) per-particle radii (as pscale). ";

/// The call's particles; every attribute given is one to carry (into s.params.attributes).
ParticleSet particlesFor(Settings& s, py::handle positions, py::handle radii, py::handle attributes)
{
    ParticleSet ps = particlesFrom(positions, radii, attributes);
    if (!attributes.is_none())
        for (auto item : py::reinterpret_borrow<py::dict>(attributes))
            s.params.attributes.push_back(py::str(item.first));
    return ps;
}

PyMesh reconstructArrays(py::handle positions, double radius, py::handle radii,
                         py::handle attributes, const py::kwargs& kwargs)
{
    Settings s = settingsFrom(kwargs, kAll);
    s.params.radius = checkedRadius(radius);
    s.params.keepGrids = false; // a Mesh is returned: the grids would only raise the peak
    const ParticleSet ps = particlesFor(s, positions, radii, attributes);
    Context ctx;
    setUp(ctx, s);
    ReconstructResult res = compute(s, ctx, [&] { return reconstruct(ps, s.params, ctx); });
    ctx.timing().finish();
    PyMesh out{std::move(res.mesh), py::dict(), std::move(res.vertexAttributes)};
    addFieldInfo(out.info, res.radius, res.field, res.isolatedParticles);
    out.info["isolated_spheres"] = res.isolatedSpheres;
    out.info["covered_particles"] = res.post.coveredParticles;
    out.info["uncovered_particles"] = res.post.uncoveredParticles;
    out.info["timing"] = ctx.timing().format();
    return out;
}

PyLevelSet rasterizeArrays(py::handle positions, double radius, py::handle radii,
                           py::handle attributes, const py::kwargs& kwargs)
{
    Settings s = settingsFrom(kwargs, kField | kRun);
    const ParticleSet ps = particlesFor(s, positions, radii, attributes);
    Context ctx;
    setUp(ctx, s);
    RadiusChoice choice;
    openvdb::GridPtrVec grids;
    RasterizeResult res = compute(s, ctx, [&] {
        choice = chooseRadius(ps, checkedRadius(radius), s.params.field.perParticleRadii, ctx);
        const Params field = s.params.fieldParams(choice.radius);
        RasterizeResult r = rasterizeParticles(ps, field, ctx);
        grids = attributeGrids(ps, s.params.attributes, *r.grid, field.influenceRadius, ctx);
        return r;
    });
    ctx.timing().finish();
    PyLevelSet out{res.grid, res.adaptive, py::dict(), std::move(grids)};
    addFieldInfo(out.info, choice, res.stats, res.isolatedParticles);
    out.info["timing"] = ctx.timing().format();
    return out;
}

void bindParticles(py::module_& m)
{
    m.def(
        "read_particles",
        [](const std::string& path, bool dropNonFinite) {
            io::ReadOptions o;
            o.dropNonFinite = dropNonFinite;
            ParticleSet ps;
            {
                py::gil_scoped_release noGil;
                ps = io::readParticles(path, o);
            }
            return particlesToDict(ps);
        },
        py::arg("path"), py::arg("drop_nonfinite") = false,
        "Read a particle frame (.vtk .vtu .vtp .bgeo .bgeo.gz .ply .xyz .csv .txt .npy .vdb) as "
        "{'positions': (N, 3) float32, attribute name: (N,) or (N, k) array, ...}.");
    m.def(
        "write_particles",
        [](const std::string& path, py::handle positions, py::handle attributes) {
            const ParticleSet ps = particlesFrom(positions, py::none(), attributes);
            py::gil_scoped_release noGil;
            io::writeParticles(ps, path);
        },
        py::arg("path"), py::arg("positions"), py::arg("attributes") = py::none(),
        "Write a particle frame (.vdb .bgeo .bgeo.gz .ply .xyz .vtk), atomically; attributes: "
        "{name: (N,) or (N, k) float or integer array}.");
    m.def(
        "generate",
        [](const std::string& scene, size_t count, double radius, uint64_t seed, double jitter,
           int layers, double poolDepth, double poolAspect, int droplets) {
            SceneParams p;
            p.count = count, p.radius = radius, p.seed = seed, p.jitter = jitter;
            p.layers = layers, p.poolDepthScale = poolDepth, p.poolAspect = poolAspect;
            p.droplets = droplets;
            const Scene sc = sceneFromName(scene);
            ParticleSet ps;
            {
                py::gil_scoped_release noGil;
                ps = generateScene(sc, p);
            }
            return particlesToDict(ps);
        },
        py::arg("scene"), py::arg("count") = SceneParams().count,
        py::arg("radius") = SceneParams().radius, py::arg("seed") = SceneParams().seed,
        py::arg("jitter") = SceneParams().jitter, py::arg("layers") = SceneParams().layers,
        py::arg("pool_depth") = SceneParams().poolDepthScale,
        py::arg("pool_aspect") = SceneParams().poolAspect,
        py::arg("droplets") = SceneParams().droplets,
        "A deterministic scene (single, block, ball, slab, drop, sheet, jet) as `fluidsurf "
        "generate` makes "
        "it, as read_particles returns particles.");
}

} // namespace

} // namespace python
} // namespace fluidsurf

PYBIND11_MODULE(fluidsurf, m)
{
    using namespace fluidsurf;
    using namespace fluidsurf::python;
    m.doc() = "fluidsurf: SPH particles to narrow-band level sets and watertight triangle meshes "
              "(Akinci 2014). reconstruct(positions, radius) -> Mesh; rasterize(...) -> LevelSet.";
    m.attr("__version__") = FLUIDSURF_VERSION_STRING;

    static py::exception<Error> error(m, "Error", PyExc_RuntimeError);
    // Python's own bases too, so that `except ValueError` and `except OSError` catch them
    static py::exception<ValueError> valueError(
        m, "ValueError", py::make_tuple(error, py::handle(PyExc_ValueError)).ptr());
    static py::exception<InputError> inputError(
        m, "InputError", py::make_tuple(error, py::handle(PyExc_OSError)).ptr());
    static py::exception<OutputError> outputError(
        m, "OutputError", py::make_tuple(error, py::handle(PyExc_OSError)).ptr());
    static py::exception<Cancelled> cancelled(m, "Cancelled", error.ptr());
    py::register_exception_translator([](std::exception_ptr p) {
        try {
            if (p) std::rethrow_exception(p);
        } catch (const ValueError& e) {
            valueError(e.what());
        } catch (const InputError& e) {
            inputError(e.what());
        } catch (const OutputError& e) {
            outputError(e.what());
        } catch (const Cancelled& e) {
            cancelled(e.what());
        } catch (const Error& e) {
            error(e.what());
        } catch (const openvdb::Exception& e) {
            error(e.what());
        }
    });

    m.def("reconstruct", &reconstructArrays, py::arg("positions"), py::arg("radius") = 0.0,
          py::kw_only(), py::arg("radii") = py::none(), py::arg("attributes") = py::none(),
          (std::string("Particles to a watertight triangle mesh, as `fluidsurf reconstruct`. ") +
           kParticlesDoc +
           "attributes: {name: (N,) or (N, k) array} carried onto the mesh's vertices "
           "(Mesh.attributes): floats by a linear fit over the particles within R (a linear "
           "field comes out exact), integers from the nearest particle. Parameters (lengths in r, "
           "as the CLI's options): " +
           describeParams(kAll) + ". Returns a Mesh.")
              .c_str());
    m.def("rasterize", &rasterizeArrays, py::arg("positions"), py::arg("radius") = 0.0,
          py::kw_only(), py::arg("radii") = py::none(), py::arg("attributes") = py::none(),
          (std::string("Particles to a narrow-band level set, as `fluidsurf rasterize`. ") +
           kParticlesDoc +
           "attributes: {name: (N,) or (N, k) array} carried onto the band as grids of its "
           "topology (LevelSet.grid_names; v as a Vec3fGrid), written with it. Parameters: " +
           describeParams(kField | kRun) + ". Returns a LevelSet.")
              .c_str());
    m.def(
        "defaults", []() { return defaults(kAll); },
        "{parameter: default} of every keyword parameter (the CLI's defaults).");
    bindParticles(m);
    bindObjects(m);
}
