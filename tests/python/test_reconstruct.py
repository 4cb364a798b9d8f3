# test_reconstruct.py - positions -> mesh in memory: the same mesh as the CLI on the same data,
# watertight by an independent count, and the level set against an analytic sphere.
import numpy as np
import pytest

import fluidsurf
from conftest import edge_problems, read_ply, run_cli

R = 0.01


def block_xyz(cli, tmp_path, count):
    """A generated block written by the CLI as raw float32 triples, read back with numpy."""
    path = tmp_path / f"block_{count}.xyz"
    run_cli(cli, "generate", "block", "-n", count, "-r", R, "-o", path)
    return path, np.fromfile(path, dtype="<f4").reshape(-1, 3)


def test_100k_block_matches_the_cli_and_is_watertight(cli, tmp_path):
    path, positions = block_xyz(cli, tmp_path, 100000)
    assert positions.shape == (46**3, 3)  # the block: round(cbrt(count)) per axis
    mesh = fluidsurf.reconstruct(positions, radius=R)
    run_cli(cli, "reconstruct", path, "-r", R, "-o", tmp_path / "cli.ply")
    vertices, triangles = read_ply(tmp_path / "cli.ply")
    assert mesh.vertices.shape == vertices.shape and mesh.vertices.dtype == np.float32
    np.testing.assert_array_equal(mesh.vertices, vertices)
    np.testing.assert_array_equal(mesh.triangles, triangles)
    assert len(mesh.triangles) > 10000
    assert edge_problems(mesh.triangles) == (0, 0, 0)
    assert mesh.check()["watertight"]
    assert mesh.normals.shape == mesh.vertices.shape
    np.testing.assert_allclose(np.linalg.norm(mesh.normals, axis=1), 1, atol=1e-4)
    assert mesh.info["radius"] == R and mesh.info["radius_source"] == "given"
    assert mesh.info["particles"] == 46**3


def test_float64_input_is_rounded_once_like_a_reader(cli, tmp_path):
    _, positions = block_xyz(cli, tmp_path, 8000)
    a = fluidsurf.reconstruct(positions, R, raw=True)
    b = fluidsurf.reconstruct(positions.astype(np.float64), R, raw=True)
    np.testing.assert_array_equal(a.vertices, b.vertices)
    # any array-like of the right shape works, Fortran order too
    c = fluidsurf.reconstruct(np.asfortranarray(positions), R, raw=True)
    np.testing.assert_array_equal(a.triangles, c.triangles)


def test_raw_matches_cli_raw_and_the_vdb_matches_rasterize(cli, tmp_path):
    path, positions = block_xyz(cli, tmp_path, 27000)
    run_cli(cli, "reconstruct", path, "-r", R, "-o", tmp_path / "raw.ply", "--raw", "--voxel",
            0.5, "--vdb", tmp_path / "cli.vdb")
    mesh = fluidsurf.reconstruct(positions, R, raw=True, voxel=0.5)
    vertices, triangles = read_ply(tmp_path / "raw.ply")
    np.testing.assert_array_equal(mesh.vertices, vertices)
    np.testing.assert_array_equal(mesh.triangles, triangles)
    ls = fluidsurf.rasterize(positions, R, voxel=0.5)
    assert ls.voxel_size == pytest.approx(0.5 * R)
    cli_ls = fluidsurf.read_level_set(str(tmp_path / "cli.vdb"))
    assert cli_ls.active_voxels == ls.active_voxels
    points = positions[::7] + np.float32(0.3 * R)
    np.testing.assert_array_equal(ls.sample(points), cli_ls.sample(points))
    again = ls.mesh()
    np.testing.assert_array_equal(again.triangles, mesh.triangles)


def test_level_set_mesh_on_the_gpu_is_the_cpus_or_a_clear_error(cli, tmp_path):
    # device="cuda" meshes on the GPU, the CPU's mesh to the byte; without a usable GPU (CI)
    # it says so
    _, positions = block_xyz(cli, tmp_path, 8000)
    ls = fluidsurf.rasterize(positions, R, voxel=0.5)
    cpu = ls.mesh()
    try:
        gpu = ls.mesh(device="cuda")
    except Exception as e:  # no usable GPU here
        assert "CUDA" in str(e)
        return
    np.testing.assert_array_equal(gpu.vertices, cpu.vertices)
    np.testing.assert_array_equal(gpu.normals, cpu.normals)
    np.testing.assert_array_equal(gpu.triangles, cpu.triangles)


def test_single_particle_level_set_is_the_sphere_of_radius_r():
    # keep_isolated: a lone particle is a sphere of radius r in the field: phi = |x - c| - r
    c = np.array([[0.1, 0.2, 0.3]])
    ls = fluidsurf.rasterize(c, R, keep_isolated=True, voxel=0.25)
    rng = np.random.default_rng(7)
    d = rng.normal(size=(500, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    dist = rng.uniform(0.6 * R, 1.6 * R, size=(500, 1))
    phi = ls.sample(c + d * dist)
    np.testing.assert_allclose(phi, dist[:, 0] - R, atol=0.05 * R)
    mesh = ls.mesh()
    assert edge_problems(mesh.triangles) == (0, 0, 0)
    radii = np.linalg.norm(mesh.vertices - c, axis=1)
    np.testing.assert_allclose(radii, R, atol=0.03 * R)
    # without keep_isolated the particle is listed, not gridded
    lone = fluidsurf.rasterize(c, R)
    assert lone.active_voxels == 0 and list(lone.info["isolated_particles"]) == [0]


def test_post_process_of_a_mesh_matches_reconstruct(cli, tmp_path):
    _, positions = block_xyz(cli, tmp_path, 8000)
    raw = fluidsurf.reconstruct(positions, R, raw=True)
    # a mesh alone keeps its own volumes (it has no particles to count)
    full = fluidsurf.reconstruct(positions, R, volume="mesh")
    post = fluidsurf.post_process(raw, voxel_size=R)
    np.testing.assert_array_equal(post.triangles, full.triangles)
    np.testing.assert_array_equal(post.vertices, full.vertices)
    assert post.info["input_triangles"] == len(raw.triangles)
    # the default brings the block to its particles' volume, N (2r)^3, where the raw surface
    # holds less; raw=True takes no volume target
    particles = fluidsurf.reconstruct(positions, R)
    block = len(positions) * (2 * R) ** 3
    assert post.check()["volume"] < 0.98 * block
    assert particles.check()["volume"] == pytest.approx(block, rel=0.01)
    with pytest.raises(ValueError, match="raw=True excludes"):
        fluidsurf.reconstruct(positions, R, raw=True, volume="mesh")
    with pytest.raises(TypeError, match="unknown parameter 'volume'"):
        fluidsurf.post_process(raw, volume="particles")


def test_mesh_from_arrays_round_trips_through_a_file(tmp_path):
    v = np.array([[0, 0, 0], [1, 0, 0], [0, 1, 0], [0, 0, 1]], dtype=np.float32)
    t = np.array([[0, 2, 1], [0, 1, 3], [0, 3, 2], [1, 2, 3]])
    m = fluidsurf.Mesh(v, t)
    report = m.check()
    assert report["watertight"] and report["volume"] == pytest.approx(1 / 6)
    m.write(str(tmp_path / "t.ply"))
    back = fluidsurf.read_mesh(str(tmp_path / "t.ply"))
    np.testing.assert_array_equal(back.vertices, v)
    np.testing.assert_array_equal(back.triangles, t)
    assert m.normals is None
    # the arrays are views of the mesh: they keep it alive
    verts = fluidsurf.Mesh(v, t).vertices
    np.testing.assert_array_equal(verts, v)


def test_adaptive_grid_has_three_grids_and_a_watertight_mesh(tmp_path):
    p = fluidsurf.generate("drop", count=30000, radius=R)
    ls = fluidsurf.rasterize(p["positions"], R, adaptive=True)
    assert ls.adaptive and ls.grid_names == ["surface", "surface_fine", "levels"]
    assert edge_problems(ls.mesh().triangles) == (0, 0, 0)
    ls.write(str(tmp_path / "a.vdb"))
    back = fluidsurf.read_level_set(str(tmp_path / "a.vdb"))
    assert back.adaptive
    mesh = fluidsurf.reconstruct(p["positions"], R, adaptive=True)
    assert edge_problems(mesh.triangles) == (0, 0, 0)
    assert len(mesh.info["isolated_particles"]) == 5  # the drop scene's droplets


def test_to_pyopenvdb():
    vdb = pytest.importorskip("pyopenvdb")
    p = fluidsurf.generate("ball", count=2000, radius=R)
    ls = fluidsurf.rasterize(p["positions"], R)
    grid = ls.to_pyopenvdb()
    assert isinstance(grid, vdb.FloatGrid) and grid.name == "surface"
    assert grid.activeVoxelCount() == ls.active_voxels
    assert grid.gridClass == vdb.GridClass.LEVEL_SET
