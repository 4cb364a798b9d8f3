# test_attributes.py - particle attributes carried onto the mesh: a rigid rotation's velocity
# against its closed form at the vertices, ids from the nearest particle, the files they go to.
import warnings

import numpy as np
import pytest

import fluidsurf
from conftest import read_ply

R = 0.01
OMEGA = np.array([0.3, 1.0, -0.5])
CENTRE = np.array([0.02, -0.01, 0.03])


def rotation(x):
    return np.cross(OMEGA, np.asarray(x, np.float64) - CENTRE)


@pytest.fixture(scope="module")
def drop():
    p = fluidsurf.generate("drop", count=30000, radius=R)
    p["v"] = rotation(p["positions"]).astype(np.float32)
    return p


def surface_error(mesh, particles):
    """Largest |v - rotation| over the vertices that are not on a droplet's sphere (a lone
    particle carries no rotation: its sphere takes its velocity), and the largest speed."""
    x = mesh.vertices.astype(np.float64)
    v = mesh.attributes["v"].astype(np.float64)
    on_sphere = np.zeros(len(x), bool)
    for j in mesh.info["isolated_particles"]:
        near = np.linalg.norm(x - particles["positions"][j], axis=1) < 1.01 * R
        np.testing.assert_allclose(v[near], particles["v"][j][None, :].repeat(near.sum(), 0),
                                   atol=1e-6)
        on_sphere |= near
    assert on_sphere.sum() > 100
    truth = rotation(x[~on_sphere])
    return np.abs(v[~on_sphere] - truth).max(), np.abs(truth).max()


@pytest.mark.parametrize("raw, bound", [(True, 0.01), (False, 0.02)])
def test_rigid_rotation_within_the_bound(drop, raw, bound):
    mesh = fluidsurf.reconstruct(drop["positions"], R, raw=raw,
                                 attributes={"v": drop["v"], "id": drop["id"]})
    assert set(mesh.attributes) == {"v", "id"}
    assert mesh.attributes["v"].shape == mesh.vertices.shape
    err, vmax = surface_error(mesh, drop)
    assert err < bound * vmax, (err, vmax)
    # ids from the nearest particle (brute force on a sample of vertices)
    rng = np.random.default_rng(1)
    for i in rng.choice(len(mesh.vertices), 200, replace=False):
        d = np.linalg.norm(drop["positions"] - mesh.vertices[i], axis=1)
        assert mesh.attributes["id"][i] == drop["id"][np.argmin(d)]


def test_attributes_go_into_ply_and_vtk_not_obj(drop, tmp_path):
    mesh = fluidsurf.reconstruct(drop["positions"], R, attributes={"v": drop["v"]})
    mesh.write(str(tmp_path / "m.ply"))
    vertices, triangles, props = read_ply(tmp_path / "m.ply", properties=True)
    np.testing.assert_array_equal(vertices, mesh.vertices)
    for c, axis in enumerate("xyz"):
        np.testing.assert_array_equal(props["v" + axis], mesh.attributes["v"][:, c])
    mesh.write(str(tmp_path / "m.vtk"))
    back = fluidsurf.read_particles(str(tmp_path / "m.vtk"))
    np.testing.assert_array_equal(back["v"], mesh.attributes["v"])
    with pytest.warns(UserWarning, match="OBJ cannot hold vertex attributes"):
        mesh.write(str(tmp_path / "m.obj"))
    assert len(fluidsurf.read_mesh(str(tmp_path / "m.obj")).triangles) == len(mesh.triangles)


def test_the_cli_writes_the_same_attributes(cli, drop, tmp_path):
    from conftest import run_cli

    fluidsurf.write_particles(str(tmp_path / "d.bgeo"), drop["positions"],
                              {"v": drop["v"], "id": drop["id"]})
    run_cli(cli, "reconstruct", tmp_path / "d.bgeo", "-r", R, "-o", tmp_path / "cli.ply",
            "--attributes", "velocity,id")
    vertices, triangles, props = read_ply(tmp_path / "cli.ply", properties=True)
    mesh = fluidsurf.reconstruct(drop["positions"], R, attributes={"v": drop["v"], "id": drop["id"]})
    np.testing.assert_array_equal(triangles, mesh.triangles)
    np.testing.assert_array_equal(props["vy"], mesh.attributes["v"][:, 1])
    np.testing.assert_array_equal(props["id"], mesh.attributes["id"])


def test_bad_attributes():
    p = fluidsurf.generate("ball", count=500, radius=R)["positions"]
    with pytest.raises(ValueError, match=r"attributes\['v'\] must have shape \(%d,\)" % len(p)):
        fluidsurf.reconstruct(p, R, attributes={"v": np.zeros((3, 3))})
    with pytest.raises(TypeError, match="attributes must be a dict"):
        fluidsurf.reconstruct(p, R, attributes=[np.zeros(len(p))])
    with pytest.raises(ValueError, match=r"attributes\['rho'\]: row 2 has a non-finite value"):
        rho = np.ones(len(p))
        rho[2] = np.nan
        fluidsurf.reconstruct(p, R, attributes={"rho": rho})
    with pytest.raises(TypeError, match="float or integer"):
        fluidsurf.reconstruct(p, R, attributes={"s": np.array(["a"] * len(p))})
    raw = fluidsurf.reconstruct(p, R, raw=True, attributes={"d": np.ones(len(p))})
    np.testing.assert_allclose(raw.attributes["d"], 1, rtol=1e-6)  # a constant stays constant
    with pytest.warns(UserWarning, match="does not carry vertex attributes"):
        assert fluidsurf.post_process(raw).attributes == {}


def test_the_vdb_holds_v_as_a_vector_grid(drop, tmp_path):
    ls = fluidsurf.rasterize(drop["positions"], R, attributes={"v": drop["v"], "id": drop["id"]})
    assert ls.grid_names == ["surface", "v", "id"]
    path = str(tmp_path / "d.vdb")
    ls.write(path)
    vdb = pytest.importorskip("pyopenvdb")
    grids = {g.name: g for g in ls.to_pyopenvdb()}
    assert set(grids) == {"surface", "v"}  # pyopenvdb has no integer grids
    v = vdb.read(path, "v")
    assert isinstance(v, vdb.Vec3SGrid) and v.activeVoxelCount() == ls.active_voxels
    surface = vdb.read(path, "surface")
    # near the surface (where a renderer samples it) v is the rotation at the voxel
    acc, sacc = v.getConstAccessor(), surface.getConstAccessor()
    dx = ls.voxel_size
    errors, vmax = [], 0.0
    for item in v.citerOnValues():
        if item.count != 1:
            continue
        ijk = item.min
        if abs(sacc.getValue(ijk)) >= 1.5 * R:
            continue
        truth = rotation(np.array(ijk, np.float64) * dx)
        errors.append(np.abs(np.array(acc.getValue(ijk)) - truth).max())
        vmax = max(vmax, np.abs(truth).max())
    assert len(errors) > 1000
    assert max(errors) < 0.01 * vmax, (max(errors), vmax)
    import shutil
    import subprocess

    if shutil.which("vdb_print"):
        out = subprocess.run(["vdb_print", path], capture_output=True, text=True).stdout
        assert any(line.split()[:2] == ["v", "vec3s"] for line in out.splitlines()), out
