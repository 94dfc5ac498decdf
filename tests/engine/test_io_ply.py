"""PLY writers: layout (double xyz, uchar rgb, one property per scalar, int vertex1/vertex2 edges),
round trip through our loader and plyfile, atomicity and input protection; XYZ/NPY writers."""

from __future__ import annotations

import numpy as np
import pytest
from plyfile import PlyData

from skelcore.errors import SkelInputError
from skelcore.io import (
    load_any,
    load_cloud,
    load_curve,
    write_curve_ply,
    write_points_npy,
    write_points_ply,
    write_points_xyz,
)


@pytest.fixture
def points(rng) -> np.ndarray:
    return rng.normal(size=(30, 3)) * 123.456


@pytest.mark.parametrize("binary", [True, False])
def test_points_ply_round_trip_with_scalars_and_colors(tmp_path, points, binary):
    path = tmp_path / "p.ply"
    score = np.linspace(0, 1, len(points))
    score[3] = np.nan
    colors = (np.arange(90).reshape(30, 3) * 2).astype(np.uint8)
    write_points_ply(path, points, scalars={"score": score}, colors=colors, binary=binary)

    ply = PlyData.read(str(path))
    assert ply.text is (not binary)
    vert = ply["vertex"]
    assert [(p.name, p.val_dtype) for p in vert.properties] == [
        ("x", "f8"), ("y", "f8"), ("z", "f8"), ("red", "u1"), ("green", "u1"), ("blue", "u1"), ("score", "f4"),
    ]  # fmt: skip
    np.testing.assert_array_equal(np.column_stack([vert["red"], vert["green"], vert["blue"]]), colors)
    got_score = np.asarray(vert["score"], dtype=np.float64)
    assert np.isnan(got_score[3])
    np.testing.assert_allclose(np.delete(got_score, 3), np.delete(score, 3), rtol=1e-6)
    # Doubles round-trip exactly (ascii through repr-precision text).
    np.testing.assert_array_equal(load_cloud(path), points)


@pytest.mark.parametrize("binary", [True, False])
def test_curve_ply_round_trip_keeps_edges_and_scalars(tmp_path, binary):
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0.5, 0], [1, 1, 0]], dtype=float)
    e = np.array([[0, 1], [1, 2], [1, 3]])
    path = tmp_path / "c.ply"
    smooth = np.array([np.nan, 0.5, np.nan, np.nan])
    write_curve_ply(path, v, e, scalars={"smoothness": smooth, "degree": np.array([1, 3, 1, 1])}, binary=binary)

    ply = PlyData.read(str(path))
    assert [el.name for el in ply.elements] == ["vertex", "edge"]
    assert [(p.name, p.val_dtype) for p in ply["edge"].properties] == [("vertex1", "i4"), ("vertex2", "i4")]
    assert ply["vertex"]["degree"].tolist() == [1, 3, 1, 1]  # integers stay integers
    assert ply["vertex"]["degree"].dtype.kind == "i"
    curve = load_curve(path)
    np.testing.assert_array_equal(curve.vertices, v)
    np.testing.assert_array_equal(curve.edges, e)
    assert load_any(path).kind == "curve"


def test_curve_without_edges_is_written_with_an_empty_edge_element(tmp_path):
    path = tmp_path / "c.ply"
    write_curve_ply(path, np.eye(3), np.empty((0, 2), dtype=int))
    assert len(PlyData.read(str(path))["edge"].data) == 0
    assert load_any(path).kind == "points"  # no edges: a dropped file of this kind is points


def test_writer_refuses_to_overwrite_a_loaded_input(tmp_path, points):
    path = tmp_path / "in.ply"
    write_points_ply(path, points)
    load_cloud(path)  # protects it
    before = path.read_bytes()
    with pytest.raises(SkelInputError, match="overwrite"):
        write_points_ply(path, points * 2)
    assert path.read_bytes() == before


def test_writer_refuses_a_path_listed_in_inputs(tmp_path, points):
    path = tmp_path / "other.ply"
    path.write_bytes(b"keep")
    with pytest.raises(SkelInputError, match="overwrite"):
        write_curve_ply(path, points, np.array([[0, 1]]), inputs=[str(path)])
    assert path.read_bytes() == b"keep"


def test_failed_write_leaves_no_file_behind(tmp_path, points):
    path = tmp_path / "bad.ply"
    with pytest.raises(ValueError):
        write_points_ply(path, points, scalars={"short": np.zeros(3)})
    with pytest.raises(ValueError):
        write_curve_ply(path, points, np.array([[0, 99]]))
    assert list(tmp_path.iterdir()) == []


@pytest.mark.parametrize(
    "kwargs",
    [
        {"scalars": {"bad name": np.zeros(30)}},
        {"scalars": {"x": np.zeros(30)}},
        {"scalars": {"red": np.zeros(30)}},  # would read as a colour even without colors=
        {"colors": np.zeros((30, 3))},  # float colours: caller forgot map_to_rgb
        {"colors": np.zeros((29, 3), dtype=np.uint8)},
    ],
)
def test_writer_rejects_bad_arguments(tmp_path, points, kwargs):
    with pytest.raises(ValueError):
        write_points_ply(tmp_path / "x.ply", points, **kwargs)


def test_xyz_and_npy_writers_round_trip_exactly(tmp_path, points):
    write_points_xyz(tmp_path / "p.xyz", points)
    write_points_npy(tmp_path / "p.npy", points)
    np.testing.assert_array_equal(load_cloud(tmp_path / "p.xyz"), points)
    np.testing.assert_array_equal(load_cloud(tmp_path / "p.npy"), points)
