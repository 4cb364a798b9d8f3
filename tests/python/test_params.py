# test_params.py - keyword parameters: the CLI's names and defaults, their effect, and refusals.
import os
import re
import subprocess

import numpy as np
import pytest

import fluidsurf

R = 0.01


@pytest.fixture(scope="module")
def ball():
    return fluidsurf.generate("ball", count=6000, radius=R)["positions"]


def cli_options(cli):
    """{name with '_': default text or None} of `fluidsurf reconstruct --help`."""
    text = subprocess.run([cli, "reconstruct", "--help"], capture_output=True, text=True).stdout
    options = {}
    option = r"^\s+(?:-\w,)?--([a-z][a-z-]*)"  # -j,--threads
    kind = r"(?: [A-Z][A-Z:]*(?: in \[[^\]]*\])?(?:\{[^}]*\})?)?"  # FLOAT:FLOAT in [0 - 1]
    for m in re.finditer(option + kind + r"(?:=(\S+))?(?:\s|$)", text, re.M):
        options[m.group(1).replace("-", "_")] = m.group(2)
    return options


def test_every_parameter_is_a_cli_option_with_the_same_default(cli):
    options = cli_options(cli)
    defaults = fluidsurf.defaults()
    assert len(defaults) >= 25
    for name, value in defaults.items():
        assert name in options, f"{name} is not an option of fluidsurf reconstruct"
        shown = options[name]
        if shown is None:  # a flag, or an option without a shown default
            assert value in (False, 0), name
        elif isinstance(value, bool):  # an on|off option, such as --flatten
            assert shown == ("on" if value else "off"), name
        elif isinstance(value, str):
            assert value == shown, name
        else:
            assert float(value) == pytest.approx(float(shown)), name


def test_parameters_change_the_result(ball):
    raw = fluidsurf.reconstruct(ball, R, raw=True)
    fine = fluidsurf.reconstruct(ball, R, raw=True, voxel=0.5)
    # half the voxel: about four times the triangles on the same surface
    assert 3.2 < len(fine.triangles) / len(raw.triangles) < 4.8
    half = fluidsurf.reconstruct(ball, R, decimate=0.5, smooth=0, subdivide=0)
    assert len(half.triangles) == pytest.approx(0.5 * len(raw.triangles), rel=0.02)
    off = fluidsurf.reconstruct(ball, R, decimate="off", smooth=0, subdivide=0)
    np.testing.assert_array_equal(off.triangles, raw.triangles)
    zb = fluidsurf.reconstruct(ball, R, raw=True, field="zb05")
    assert not np.array_equal(zb.vertices, raw.vertices) or len(zb.vertices) != len(raw.vertices)
    one = fluidsurf.reconstruct(ball, R, threads=1)
    many = fluidsurf.reconstruct(ball, R, threads=2)
    np.testing.assert_array_equal(one.vertices, many.vertices)


def test_flatten_moves_the_points_of_flat_fluid_only():
    slab = fluidsurf.generate("slab", count=20000, radius=R, layers=6, jitter=0.3)["positions"]
    flat = fluidsurf.reconstruct(slab, R)
    unflattened = fluidsurf.reconstruct(slab, R, flatten=False)
    np.testing.assert_array_equal(flat.triangles, unflattened.triangles)
    moved = np.linalg.norm(flat.vertices - unflattened.vertices, axis=1)
    assert moved.max() > 0.05 * R
    # (0.4 voxel of flattening where the smoothing had 0.2, the volume offset on top)
    assert moved.max() < 0.6 * R


def test_cover_moves_points_over_the_centres_left_outside():
    frame = os.path.join(os.path.dirname(__file__), "../../../shared/data/real",
                         "double_dam_break_frame_26_4732_particles.vtk")
    if not os.path.exists(frame):
        pytest.skip("../shared/data/real is absent")
    positions = fluidsurf.read_particles(frame)["positions"]
    r = 0.025
    covered = fluidsurf.reconstruct(positions, r)
    open_ = fluidsurf.reconstruct(positions, r, cover=False)
    assert covered.info["covered_particles"] > 0
    assert open_.info["covered_particles"] == 0
    np.testing.assert_array_equal(covered.triangles, open_.triangles)
    moved = np.linalg.norm(covered.vertices - open_.vertices, axis=1)
    # bumps of at most a voxel and the margin (r here) near each centre; the rest stays
    assert 0 < moved.max() < 2 * 1.1 * r
    assert np.count_nonzero(moved) < 0.05 * len(moved)


def test_radii_and_the_radius_choice(ball):
    given = fluidsurf.reconstruct(ball, R, raw=True)
    radii = np.full(len(ball), R, dtype=np.float32)
    from_radii = fluidsurf.reconstruct(ball, radii=radii, raw=True)
    assert from_radii.info["radius_source"] == "attribute"
    np.testing.assert_array_equal(from_radii.triangles, given.triangles)
    estimated = fluidsurf.reconstruct(ball, raw=True)
    assert estimated.info["radius_source"] == "estimate"
    assert estimated.info["radius"] == pytest.approx(R, rel=0.01)  # half the lattice spacing
    # bigger radii on half the particles change the surface, unless ignored
    radii[::2] = 1.5 * R
    varied = fluidsurf.reconstruct(ball, R, radii=radii, raw=True)
    ignored = fluidsurf.reconstruct(ball, R, radii=radii, raw=True, ignore_radius_attribute=True)
    assert not np.array_equal(varied.vertices, given.vertices)
    np.testing.assert_array_equal(ignored.vertices, given.vertices)


@pytest.mark.parametrize(
    "kwargs, error, message",
    [
        ({"voxel": -1}, fluidsurf.ValueError, "voxel must be a positive finite number (got -1)"),
        ({"voxel": float("nan")}, ValueError, "voxel must be a positive finite number (got nan)"),
        ({"voxel": "1"}, TypeError, "voxel must be a number (got str)"),
        ({"smooth": 2.5}, TypeError, "smooth must be an int (got float)"),
        ({"subdivide": 4}, ValueError, "subdivide must be in [0, 3] (got 4)"),
        ({"adaptive": 1}, TypeError, "adaptive must be True or False (got int)"),
        ({"field": "zb06"}, ValueError, "unknown field 'zb06' (ssp07, zb05, ssp07-aniso, yt10)"),
        ({"field": "yt10", "iso_level": 1.5}, ValueError, "iso level must be in (0, 1)"),
        ({"decimate": 1.0}, ValueError, "decimate must be a fraction in [0, 1) or 'off'"),
        ({"raw": True, "smooth": 3}, ValueError, "raw=True excludes"),
        ({"raw": True, "flatten": False}, ValueError, "raw=True excludes"),
        ({"flatten": "off"}, TypeError, "flatten must be True or False (got str)"),
        ({"raw": True, "cover": False}, ValueError, "raw=True excludes"),
        ({"cover": 0}, TypeError, "cover must be True or False (got int)"),
        ({"voxels": 1.0}, TypeError, "unknown parameter 'voxels' (known: voxel=1.0, "),
        ({"t_low": 4.0}, ValueError, "t_low must be smaller than t_high"),
        ({"device": "tpu"}, ValueError, "tpu"),
    ],
)
def test_bad_parameters_are_exceptions_with_the_cli_messages(ball, kwargs, error, message):
    with pytest.raises(error) as e:
        fluidsurf.reconstruct(ball, R, **kwargs)
    assert message in str(e.value)


def test_parameters_a_call_does_not_take_are_refused(ball):
    with pytest.raises(TypeError, match="unknown parameter 'decimate'"):
        fluidsurf.rasterize(ball, R, decimate=0.5)
    raw = fluidsurf.reconstruct(ball, R, raw=True)
    with pytest.raises(TypeError, match="unknown parameter 'isolated'"):
        fluidsurf.post_process(raw, isolated="drop")
    with pytest.raises(TypeError, match="unknown parameter 'voxel'"):
        fluidsurf.rasterize(ball, R).mesh(voxel=2.0)


def test_docstrings_list_the_parameters():
    assert "voxel=1.0" in fluidsurf.reconstruct.__doc__
    assert "decimate=0.8" in fluidsurf.reconstruct.__doc__
    assert "decimate" not in fluidsurf.rasterize.__doc__.split("Parameters:")[1]
