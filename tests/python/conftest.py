# conftest.py - what the Python package's tests share: the module (from PYTHONPATH, as ctest sets
# it to the build tree), the CLI it is compared with, and an independent reader of the CLI's meshes.
import os
import subprocess

import numpy as np
import pytest


@pytest.fixture(scope="session")
def cli():
    path = os.environ.get("FLUIDSURF_CLI")
    if not path or not os.path.exists(path):
        pytest.skip("FLUIDSURF_CLI (the fluidsurf program) is not set")
    return path


def run_cli(cli, *args):
    subprocess.run([cli, *map(str, args)], check=True, capture_output=True, text=True)


def read_ply(path, properties=False):
    """Vertices (V, 3) float32 and triangles (T, 3) of a binary little-endian PLY, read with numpy
    alone (independent of the library's reader); with properties=True also {name: (V,) array}
    of every vertex property."""
    with open(path, "rb") as f:
        data = f.read()
    end = data.index(b"end_header\n") + len(b"end_header\n")
    header = data[:end].decode().splitlines()
    assert header[1] == "format binary_little_endian 1.0"
    counts, props, current = {}, {"vertex": [], "face": []}, None
    for line in header:
        words = line.split()
        if words[0] == "element":
            current = words[1]
            counts[current] = int(words[2])
        elif words[0] == "property" and words[1] != "list":
            props[current].append((words[1], words[2]))
        elif words[0] == "property":
            assert words[2:4] == ["uchar", "int"], words
    types = {"float": "<f4", "int": "<i4"}
    vdtype = np.dtype([(name, types[t]) for t, name in props["vertex"]])
    v = np.frombuffer(data, vdtype, counts["vertex"], end)
    xyz = np.stack([v["x"], v["y"], v["z"]], axis=1)
    fdtype = np.dtype([("n", "u1"), ("i", "<i4", 3)])
    faces = np.frombuffer(data, fdtype, counts["face"], end + vdtype.itemsize * counts["vertex"])
    assert (faces["n"] == 3).all()
    if properties:
        return xyz, faces["i"].copy(), {name: v[name].copy() for _, name in props["vertex"]}
    return xyz, faces["i"].copy()


def edge_problems(triangles):
    """Boundary edges, non-manifold edges and misoriented edges of a triangle array, counted
    with numpy (independent of checkMesh): in a closed oriented manifold every directed edge
    occurs once and its reverse once."""
    t = np.asarray(triangles, dtype=np.int64)
    directed = np.concatenate([t[:, [0, 1]], t[:, [1, 2]], t[:, [2, 0]]])
    undirected = np.sort(directed, axis=1)
    _, uses = np.unique(undirected, axis=0, return_counts=True)
    _, dir_uses = np.unique(directed, axis=0, return_counts=True)
    return int((uses == 1).sum()), int((uses > 2).sum()), int((dir_uses > 1).sum())
