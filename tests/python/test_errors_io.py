# test_errors_io.py - bad arrays and files are Python exceptions with clear messages (never a
# crash), and the readers and writers round-trip particles with their attributes.
import numpy as np
import pytest

import fluidsurf

R = 0.01


@pytest.mark.parametrize(
    "positions, error, message",
    [
        (np.zeros((10, 2), np.float32), ValueError, "positions must have shape (N, 3) (got (10, 2))"),
        (np.zeros(30, np.float32), ValueError, "positions must have shape (N, 3) (got (30,))"),
        (np.zeros((10, 3), np.int64), TypeError, "positions must be float32 or float64 (got int64)"),
        (np.zeros((10, 3), np.float16), TypeError, "float32 or float64 (got float16)"),
        ("particles", TypeError, "positions must be float32 or float64 (got <U9)"),
        (np.array([[0, 0, 0], [np.nan, 0, 0]]), ValueError, "positions: row 1 has a non-finite value (nan)"),
        (np.array([[0, 0, 0], [0, 0, -np.inf]]), ValueError, "row 1 has a non-finite value (-inf)"),
        (np.array([[0, 0, 0], [0, 1e300, 0]]), ValueError, "row 1 has a value beyond float32's range"),
    ],
)
def test_bad_positions(positions, error, message):
    with pytest.raises(error) as e:
        fluidsurf.reconstruct(positions, R)
    assert message in str(e.value)
    with pytest.raises(error):
        fluidsurf.rasterize(positions, R)


def test_bad_radii_and_radius():
    p = fluidsurf.generate("ball", count=500, radius=R)["positions"]
    with pytest.raises(ValueError, match=r"radii must have shape \(%d,\)" % len(p)):
        fluidsurf.reconstruct(p, radii=np.ones(3))
    with pytest.raises(ValueError, match="radius must be a positive finite number, or 0"):
        fluidsurf.reconstruct(p, -R)
    with pytest.raises(fluidsurf.ValueError):
        fluidsurf.reconstruct(p, radii=np.full(len(p), -R))  # the library's own check
    # no particles: no surface, and no error (a frame of a sequence may be empty)
    assert len(fluidsurf.reconstruct(np.zeros((0, 3), np.float32), R).triangles) == 0


def test_bad_meshes():
    v = np.zeros((3, 3), np.float32)
    with pytest.raises(ValueError, match="triangles: row 0 has index 3, outside 0..2"):
        fluidsurf.Mesh(v, [[0, 1, 3]])
    with pytest.raises(ValueError, match="triangles must have shape"):
        fluidsurf.Mesh(v, [0, 1, 2])
    with pytest.raises(ValueError, match="normals must have one row per vertex"):
        fluidsurf.Mesh(v, [[0, 1, 2]], normals=np.zeros((2, 3)))


def test_file_errors_name_the_file(tmp_path):
    missing = str(tmp_path / "none.bgeo")
    with pytest.raises(fluidsurf.InputError) as e:
        fluidsurf.read_particles(missing)
    assert missing in str(e.value) and isinstance(e.value, OSError)
    corrupt = tmp_path / "bad.bgeo"
    corrupt.write_bytes(b"BgeoV\x00\x00\x00\x05garbage")
    with pytest.raises(fluidsurf.InputError, match="bad.bgeo"):
        fluidsurf.read_particles(str(corrupt))
    with pytest.raises(fluidsurf.InputError, match="bad.vdb"):
        (tmp_path / "bad.vdb").write_bytes(b"not a vdb")
        fluidsurf.read_level_set(str(tmp_path / "bad.vdb"))
    p = fluidsurf.generate("block", count=64, radius=R)["positions"]
    with pytest.raises(fluidsurf.OutputError):
        fluidsurf.write_particles(str(tmp_path / "p.unknown"), p)
    with pytest.raises(fluidsurf.OutputError):
        fluidsurf.write_particles(str(tmp_path / "no" / "dir" / "p.bgeo"), p)
    assert sorted(f.name for f in tmp_path.iterdir()) == ["bad.bgeo", "bad.vdb"]  # no partial file


@pytest.mark.parametrize("ext", [".bgeo", ".vtk", ".ply", ".vdb"])
def test_particles_round_trip_with_attributes(tmp_path, ext):
    rng = np.random.default_rng(3)
    n = 1000
    p = rng.uniform(-1, 1, (n, 3)).astype(np.float32)
    attributes = {
        "v": rng.normal(size=(n, 3)).astype(np.float32),
        "density": rng.uniform(990, 1010, n),
        "id": np.arange(n, dtype=np.int32)[::-1].copy(),
    }
    path = str(tmp_path / ("frame" + ext))
    fluidsurf.write_particles(path, p, attributes)
    back = fluidsurf.read_particles(path)
    order = np.argsort(back["id"])[::-1] if ext == ".vdb" else np.arange(n)  # VDB reorders
    np.testing.assert_array_equal(back["positions"][order], p)
    np.testing.assert_array_equal(back["v"][order], attributes["v"])
    np.testing.assert_array_equal(back["density"][order], attributes["density"].astype(np.float32))
    np.testing.assert_array_equal(back["id"][order], attributes["id"])
    assert back["id"].dtype == np.int64 and back["v"].shape == (n, 3)


def test_generate_matches_the_cli(cli, tmp_path):
    from conftest import run_cli

    run_cli(cli, "generate", "drop", "-n", 5000, "-r", R, "-o", tmp_path / "d.xyz")
    ours = fluidsurf.generate("drop", count=5000, radius=R)
    np.testing.assert_array_equal(
        ours["positions"], np.fromfile(tmp_path / "d.xyz", "<f4").reshape(-1, 3))
    with pytest.raises(ValueError, match="scene"):
        fluidsurf.generate("cube")


def test_ragged_and_odd_lists_are_type_errors():
    # a ragged list made a null array that was then used: a segfault (issue 63)
    for positions in ([[0, 0, 0], [1, 1]], [[0, 0, 0], "abc"], [[0, 0, 0], [1, [2], 3]]):
        with pytest.raises((TypeError, ValueError)):
            fluidsurf.reconstruct(positions, 0.01)
        with pytest.raises((TypeError, ValueError)):
            fluidsurf.rasterize(positions, 0.01)
    with pytest.raises(TypeError, match="must be an array"):
        fluidsurf.reconstruct([[0, 0, 0], [1, 1]], 0.01)


def test_thread_counts_are_bounded():
    p = fluidsurf.generate("ball", count=500, radius=R)["positions"]
    for threads in (-1, 4097, 70000):
        with pytest.raises(ValueError, match="threads"):
            fluidsurf.reconstruct(p, R, threads=threads)
    assert len(fluidsurf.reconstruct(p, R, threads=4096, raw=True).triangles) > 0


def test_a_nul_in_a_name_is_refused(tmp_path):
    p = fluidsurf.generate("ball", count=500, radius=R)["positions"]
    m = fluidsurf.reconstruct(p, R, raw=True)
    with pytest.raises(fluidsurf.OutputError):
        m.write(str(tmp_path / "a\x00b.obj"))
    assert list(tmp_path.iterdir()) == []
