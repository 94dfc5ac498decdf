"""Fuzz the loaders: random truncations and byte flips of valid files of every format must give
either a successful load or a one-line SkelInputError, never another exception (seeded, fast). The
PLY layouts with list properties (faces before the vertices, polylines as edges, ASCII and binary)
are fuzzed beside the formats' files."""

from __future__ import annotations

import warnings

import numpy as np
import pytest
from plyfile import PlyData, PlyElement
from test_io_formats import CURVE_BRANCHES, CLOUD_WRITERS, CURVE_WRITERS, make_cloud, make_curve

from skelcore.errors import SkelInputError
from skelcore.io import load_any, load_cloud, load_curve

CASES_PER_FILE = 24


def _mutations(data: bytes, rng: np.random.Generator, n: int):
    """Half truncations (anywhere, biased to the header), half 1-4 byte flips; then one of each kind."""
    for k in range(n):
        if k % 2 == 0:
            cut = int(rng.integers(0, min(len(data), 200))) if k % 4 == 0 else int(rng.integers(0, len(data)))
            yield f"cut{cut}", data[:cut]
        else:
            buf = bytearray(data)
            for _ in range(int(rng.integers(1, 5))):
                pos = int(rng.integers(0, min(len(buf), 160))) if k % 4 == 1 else int(rng.integers(0, len(buf)))
                buf[pos] = int(rng.integers(0, 256))
            yield f"flip{k}", bytes(buf)


def _check(path, loader) -> str:
    try:
        with warnings.catch_warnings():
            warnings.simplefilter("ignore")  # NaN vertices dropped by CurveSkeleton.from_raw
            loader(path)
    except SkelInputError as err:
        msg = str(err)
        assert "\n" not in msg and path.name in msg, msg
        return "error"
    return "ok"


def _vertices(pts: np.ndarray, normals: bool = False) -> PlyElement:
    fields = [("x", "f4"), ("y", "f4"), ("z", "f4")] + [("normals", object)] * normals
    vert = np.empty(len(pts), dtype=fields)
    vert["x"], vert["y"], vert["z"] = pts.T
    if normals:
        vert["normals"] = [np.ones(k % 3, dtype="f4") for k in range(len(pts))]  # lengths vary
    return PlyElement.describe(vert, "vertex", len_types={"normals": "u1"}, val_types={"normals": "f4"})


def _faces(n: int) -> PlyElement:
    face = np.empty(n, dtype=[("vertex_indices", object), ("flags", "u2")])
    face["vertex_indices"] = [np.arange(3 + k % 2, dtype=np.int32) for k in range(n)]
    face["flags"] = np.arange(n)
    return PlyElement.describe(face, "face", len_types={"vertex_indices": "u1"}, val_types={"vertex_indices": "i4"})


def _write_faces_first(path, pts, *, text: bool) -> None:
    PlyData([_faces(5), _vertices(pts, normals=True)], text=text, byte_order="<").write(str(path))


def _write_polylines(path, v, e, *, text: bool) -> None:
    lines = np.empty(len(CURVE_BRANCHES), dtype=[("vertex_indices", object)])
    lines["vertex_indices"] = [np.array(b, dtype=np.int32) for b in CURVE_BRANCHES]
    edge = PlyElement.describe(lines, "edge", len_types={"vertex_indices": "u2"}, val_types={"vertex_indices": "i4"})
    PlyData([_faces(2), _vertices(v), edge], text=text, byte_order=">").write(str(path))


PLY_CLOUDS = {
    "ply_faces_first_binary": (".ply", lambda path, pts: _write_faces_first(path, pts, text=False)),
    "ply_faces_first_ascii": (".ply", lambda path, pts: _write_faces_first(path, pts, text=True)),
}
PLY_CURVES = {
    "ply_polylines_binary": (".ply", lambda path, v, e: _write_polylines(path, v, e, text=False)),
    "ply_polylines_ascii": (".ply", lambda path, v, e: _write_polylines(path, v, e, text=True)),
}
CLOUDS, CURVES = {**CLOUD_WRITERS, **PLY_CLOUDS}, {**CURVE_WRITERS, **PLY_CURVES}
FILES = [("cloud", n) for n in sorted(CLOUDS)] + [("curve", n) for n in sorted(CURVES)]


@pytest.mark.parametrize("kind,name", FILES)
def test_corrupted_files_raise_only_skelinputerror(tmp_path, kind, name):
    seed = sum(map(ord, name))
    rng = np.random.default_rng(seed)
    src = tmp_path / "src"
    src.mkdir()
    if kind == "cloud":
        suffix, writer = CLOUDS[name]
        good = src / f"good{suffix}"
        writer(good, make_cloud(12, seed=seed))
        loaders = (load_cloud, load_any)
    else:
        suffix, writer = CURVES[name]
        good = src / f"good{suffix}"
        writer(good, *make_curve())
        loaders = (load_curve, load_any)
    data = good.read_bytes()
    outcomes = {"ok": 0, "error": 0}
    for tag, mutated in _mutations(data, rng, CASES_PER_FILE):
        path = tmp_path / f"{tag}{suffix}"
        path.write_bytes(mutated)
        for loader in loaders:
            outcomes[_check(path, loader)] += 1
    # The cases must actually exercise the error paths (a truncation to 0 bytes always fails).
    assert outcomes["error"] > 0
