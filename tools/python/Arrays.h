// Arrays.h - NumPy arrays <-> the library's data (ParticleSet, TriangleMesh), checked on the way
// in: a wrong shape, dtype or a non-finite value is a Python exception naming the argument, never
// a crash or a silently converted value. Coordinates are float32, as every reader gives them:
// float64 input is rounded once.
#pragma once

#include <fluidsurf/Mesh.h>
#include <fluidsurf/ParticleSet.h>

#include <pybind11/numpy.h>
#include <pybind11/pybind11.h>

#include <string>

namespace fluidsurf {
namespace python {

/// An (N, 3) float32/float64 array of finite coordinates -> points. name is the argument's.
std::vector<Vec3f> pointsFrom(pybind11::handle array, const char* name);

/// Particles from positions, optional per-particle radii (N,) (stored as "pscale") and optional
/// attributes {name: (N,) or (N, k) array} (floats as float32, integers as int64).
ParticleSet particlesFrom(pybind11::handle positions, pybind11::handle radii,
                          pybind11::handle attributes);

/// Attributes from {name: (rows,) or (rows, k) array} (None: none), checked as above.
std::vector<Attribute> attributesFrom(pybind11::handle attributes, size_t rows);
/// {name: (rows,) or (rows, k) array} (float32 or int64), copies.
pybind11::dict attributesToDict(const std::vector<Attribute>& attributes, size_t rows);

/// {"positions": (N, 3) float32, attribute name: (N,) or (N, k) array, ...}
pybind11::dict particlesToDict(const ParticleSet& particles);

/// A mesh from vertices (V, 3), triangles (T, 3) of indices < V, and optional normals (V, 3).
TriangleMesh meshFrom(pybind11::handle vertices, pybind11::handle triangles,
                      pybind11::handle normals);

/// (rows, 3) views of a vector's memory, kept alive by owner (the Python object holding it).
pybind11::array_t<float> view(std::vector<Vec3f>& v, pybind11::handle owner);
pybind11::array_t<uint32_t> view(std::vector<std::array<uint32_t, 3>>& v, pybind11::handle owner);

} // namespace python
} // namespace fluidsurf
