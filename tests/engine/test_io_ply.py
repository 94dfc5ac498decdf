"""PLY writers: layout (double xyz, uchar rgb, one property per scalar, int vertex1/vertex2 edges),
round trip through our loader and plyfile, atomicity and input protection; XYZ/NPY writers. The PLY
reader and writer against plyfile (random layouts both ways); the package runs without plyfile."""

from __future__ import annotations

import io
import subprocess
import sys
import warnings
from pathlib import Path

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from hypothesis.extra import numpy as hnp
from plyfile import PlyData, PlyElement, PlyListProperty

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
from skelcore.io.ply import PlyList, read_ply, read_ply_elements


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


# ---- the reader and the writer against plyfile, the independent reference ------------------------

# plyfile's type name: (numpy code, the names a header may give it)
PLY_TYPES = {
    "char": ("i1", ["char", "int8", "i1"]), "uchar": ("u1", ["uchar", "uint8", "u1"]),
    "short": ("i2", ["short", "int16", "i2"]), "ushort": ("u2", ["ushort", "uint16", "u2"]),
    "int": ("i4", ["int", "int32", "i4"]), "uint": ("u4", ["uint", "uint32", "u4"]),
    "float": ("f4", ["float", "float32", "f4"]), "double": ("f8", ["double", "float64", "f8"]),
}  # fmt: skip
LEN_TYPES = ["u1", "i1", "u2", "i2", "i4", "u4"]  # of a list's length
ELEMENT_NAMES = ["vertex", "face", "edge", "material", "range_grid", "tristrips"]


def _plyfile_bytes(elements, fmt: str, comments=(), obj_info=()) -> bytes:
    ply = PlyData(elements, text=fmt == "ascii", byte_order=fmt if fmt != "ascii" else "=", comments=list(comments),
                  obj_info=list(obj_info))  # fmt: skip
    buf = io.BytesIO()
    ply.write(buf)
    return buf.getvalue()


def _read_reference(data: bytes) -> PlyData:
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # plyfile's loadtxt warns on an empty ASCII list
        return PlyData.read(io.BytesIO(data))


def _respell(data: bytes, names: dict[str, str], newline: bytes) -> bytes:
    """The header with every type under another of its names, its lines ended by ``newline`` (LF, CRLF
    or CR; the ASCII data's too)."""
    head, sep, body = data.partition(b"end_header\n")
    lines = []
    for line in head.decode("ascii").split("\n"):
        words = line.split(" ")
        if words[0] == "property":
            words = [words[0], *(names.get(w, w) for w in words[1:-1]), words[-1]]
        lines.append(" ".join(words))
    head = "\n".join(lines).encode("ascii").replace(b"\n", newline)
    if b"format ascii" in head:
        body = body.replace(b"\n", newline)
    return head + b"end_header" + newline + body


@st.composite
def ply_layouts(draw) -> tuple[bytes, bytes]:
    """(file as plyfile writes it, the same file respelled): 1-3 elements of 0-6 rows in any order,
    1-4 scalar or list properties of any type (lists of constant or varying length), any format."""
    names = draw(st.lists(st.sampled_from(ELEMENT_NAMES), min_size=1, max_size=3, unique=True))
    elements = []
    for name in names:
        count = draw(st.integers(0, 6))
        fields, columns, len_types, val_types = [], {}, {}, {}
        for j in range(draw(st.integers(1, 4))):
            prop, code = f"p{j}", PLY_TYPES[draw(st.sampled_from(sorted(PLY_TYPES)))][0]
            if draw(st.booleans()):  # a list property
                lengths = draw(st.lists(st.integers(0, 5), min_size=count, max_size=count))
                if draw(st.booleans()):  # one length for every row
                    lengths = [draw(st.integers(0, 4))] * count
                rows = np.empty(count, dtype=object)
                for k, n in enumerate(lengths):
                    rows[k] = draw(hnp.arrays(np.dtype(code), n))
                fields.append((prop, object))
                columns[prop] = rows
                len_types[prop], val_types[prop] = draw(st.sampled_from(LEN_TYPES)), code
            else:
                fields.append((prop, code))
                columns[prop] = draw(hnp.arrays(np.dtype(code), count))
        arr = np.empty(count, dtype=fields)
        for prop, col in columns.items():
            arr[prop] = col
        comments = draw(st.lists(st.sampled_from(["made by a test", "units: mm"]), max_size=1))
        elements.append(PlyElement.describe(arr, name, len_types=len_types, val_types=val_types, comments=comments))
    obj_info = draw(st.lists(st.just("num_cols 1"), max_size=1))
    data = _plyfile_bytes(elements, draw(st.sampled_from(["ascii", "<", ">"])), ["a comment"], obj_info)
    spelling = {name: draw(st.sampled_from(aliases)) for name, (_, aliases) in PLY_TYPES.items()}
    return data, _respell(data, spelling, newline=draw(st.sampled_from([b"\n", b"\r\n", b"\r"])))


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(ply_layouts())
def test_reader_reads_every_layout_as_plyfile_does(layout):
    """Every element and property, scalar or list, of every type, format and line end: the same
    values as plyfile's (exactly; NaN where NaN), binary columns of the declared type."""
    original, respelled = layout
    ref = _read_reference(original)
    got = read_ply_elements("random.ply", respelled)
    assert list(got) == [el.name for el in ref.elements]
    for el in ref.elements:
        assert list(got[el.name]) == [p.name for p in el.properties]
        for prop in el.properties:
            ours, theirs = got[el.name][prop.name], el.data[prop.name]
            if isinstance(prop, PlyListProperty):
                assert isinstance(ours, PlyList)
                rows = ours.rows()
                assert len(rows) == len(theirs)
                for a, b in zip(rows, theirs):
                    _assert_same_values(a, b, ref.text)
            else:
                _assert_same_values(ours, theirs, ref.text)


def _assert_same_values(ours: np.ndarray, theirs: np.ndarray, text: bool) -> None:
    """Binary: the declared type (in the file's byte order) and the same values. ASCII: our reader keeps
    the text's values (float64), plyfile rounds them to the declared type: equal once rounded alike."""
    theirs = np.asarray(theirs)
    if text:
        assert ours.dtype == np.float64
        ours = ours.astype(theirs.dtype)
    else:
        assert (ours.dtype.kind, ours.dtype.itemsize) == (theirs.dtype.kind, theirs.dtype.itemsize)
    np.testing.assert_array_equal(np.asarray(ours, dtype=np.float64), np.asarray(theirs, dtype=np.float64))


@st.composite
def curve_layouts(draw) -> bytes:
    """A curve as other tools write it: x y z of any numeric type, maybe a radius and a list property
    in the vertices, edges as vertex1/vertex2 pairs or as polylines (a list per row), other elements
    (faces, materials) before or after, any format."""
    nv = draw(st.integers(1, 8))
    vfields = [(k, PLY_TYPES[draw(st.sampled_from(sorted(PLY_TYPES)))][0]) for k in "xyz"]
    has_radius, has_normals = draw(st.booleans()), draw(st.booleans())
    vfields += [("radius", "f4")] * has_radius + [("normals", object)] * has_normals
    vert = np.empty(nv, dtype=vfields)
    for k, code in vfields[:3]:
        vert[k] = draw(hnp.arrays(np.dtype(code), nv, elements=st.integers(0, 100)))
    if has_radius:
        vert["radius"] = draw(hnp.arrays(np.dtype("f4"), nv, elements=st.floats(0.5, 2, width=32)))
    if has_normals:
        vert["normals"] = [np.zeros(draw(st.integers(0, 3)), dtype="f4") for _ in range(nv)]
    index = st.integers(0, nv - 1)
    if draw(st.booleans()):  # pairs
        code = draw(st.sampled_from(["i4", "u4", "i2", "u1"]))
        pairs = np.array(draw(st.lists(st.tuples(index, index), max_size=6)), dtype=np.int64).reshape(-1, 2)
        edge = np.empty(len(pairs), dtype=[("vertex1", code), ("vertex2", code)])
        edge["vertex1"], edge["vertex2"] = pairs[:, 0], pairs[:, 1]
        edge_el = PlyElement.describe(edge, "edge")
    else:  # polylines
        lines = draw(st.lists(st.lists(index, max_size=5), max_size=4))
        edge = np.empty(len(lines), dtype=[("vertex_indices", object)])
        edge["vertex_indices"] = [np.array(line, dtype=np.int32) for line in lines]
        edge_el = PlyElement.describe(edge, "edge", len_types={"vertex_indices": draw(st.sampled_from(LEN_TYPES))},
                                      val_types={"vertex_indices": "i4"})  # fmt: skip
    face = np.empty(draw(st.integers(0, 3)), dtype=[("vertex_indices", object)])
    face["vertex_indices"] = [np.arange(draw(st.integers(3, 4)), dtype=np.int32) for _ in range(len(face))]
    material = np.zeros(draw(st.integers(0, 2)), dtype=[("ambient_red", "u1"), ("shininess", "f4")])
    elements = [PlyElement.describe(vert, "vertex"), edge_el, PlyElement.describe(face, "face"),
                PlyElement.describe(material, "material")]  # fmt: skip
    return _plyfile_bytes(draw(st.permutations(elements)), draw(st.sampled_from(["ascii", "<", ">"])))


@settings(max_examples=80, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(curve_layouts())
def test_curves_of_every_layout_load_as_plyfile_reads_them(data):
    """The vertices, radius and edges (pairs, or consecutive indices of each polyline) of plyfile's
    reading. (plyfile writes the scalars of a big-endian element that has a list in the machine's
    byte order; both readers follow the header, so the expected values are plyfile's reading.)"""
    ref = _read_reference(data)
    vert, edge = ref["vertex"], ref["edge"]
    raw = read_ply(Path("curve.ply"), data)
    np.testing.assert_array_equal(raw.vertices, np.column_stack([vert[k].astype(np.float64) for k in "xyz"]))
    if "radius" in vert:
        np.testing.assert_array_equal(raw.radius, vert["radius"].astype(np.float64))
    else:
        assert raw.radius is None
    if "vertex1" in edge:
        pairs = np.column_stack([edge["vertex1"], edge["vertex2"]]).astype(np.int64)
    else:
        pairs = np.array([(a, b) for line in edge["vertex_indices"] for a, b in zip(line[:-1], line[1:])])
    np.testing.assert_array_equal(raw.edges, pairs.reshape(-1, 2))


@st.composite
def written_sets(draw) -> dict:
    n = draw(st.integers(0, 12))
    points = draw(hnp.arrays(np.float64, (n, 3), elements=st.floats(allow_nan=True, allow_infinity=True)))
    scalars = {}
    for name in draw(st.lists(st.sampled_from(["score", "degree", "radius", "label"]), unique=True, max_size=3)):
        if name in ("degree", "label"):
            scalars[name] = draw(hnp.arrays(np.int32, n))
        else:
            scalars[name] = draw(hnp.arrays(np.float64, n, elements=st.floats(width=32)))
    colors = draw(st.none() | hnp.arrays(np.uint8, (n, 3)))
    edges = None
    if n and draw(st.booleans()):
        edges = np.array(draw(st.lists(st.tuples(st.integers(0, n - 1), st.integers(0, n - 1)), max_size=8)))
    return {"points": points, "scalars": scalars, "colors": colors, "edges": edges, "binary": draw(st.booleans()),
            "comments": draw(st.lists(st.sampled_from(["colour by score", "two\nlines"]), max_size=2))}  # fmt: skip


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(written_sets())
def test_plyfile_reads_what_we_write(tmp_path_factory, case):
    """Our files, binary and ASCII, read by plyfile: the layout and every value as written (coordinates
    and a radius as doubles, other float scalars as floats, integers as ints); our reader agrees."""
    path = tmp_path_factory.mktemp("written") / "out.ply"
    kw = {"scalars": case["scalars"], "colors": case["colors"], "binary": case["binary"], "comments": case["comments"]}
    if case["edges"] is None:
        write_points_ply(path, case["points"], **kw)
    else:
        write_curve_ply(path, case["points"], case["edges"], **kw)
    ply = PlyData.read(str(path))
    assert ply.text is not case["binary"]
    assert ply.comments == ["written by skelcore", *(" ".join(c.split()) for c in case["comments"])]
    vert = ply["vertex"]
    for j, k in enumerate("xyz"):
        assert vert[k].dtype == np.float64
        np.testing.assert_array_equal(vert[k], case["points"][:, j])
    if case["colors"] is not None:
        np.testing.assert_array_equal(np.column_stack([vert["red"], vert["green"], vert["blue"]]), case["colors"])
    for name, values in case["scalars"].items():
        want = values if name != "score" else values.astype(np.float32)
        assert vert[name].dtype == want.dtype
        np.testing.assert_array_equal(vert[name], want)
    if case["edges"] is not None:
        edge = ply["edge"]
        np.testing.assert_array_equal(np.column_stack([edge["vertex1"], edge["vertex2"]]).reshape(-1, 2),
                                      case["edges"].reshape(-1, 2))  # fmt: skip
    ours = read_ply_elements(path, path.read_bytes())
    for el in ply.elements:
        for prop in el.properties:
            _assert_same_values(ours[el.name][prop.name], el.data[prop.name], ply.text)


@pytest.mark.parametrize("binary", [True, False])
def test_header_comments_stay_ascii(tmp_path, points, binary):
    """A PLY header is ASCII: other characters of a comment are written as backslash escapes."""
    path = tmp_path / "p.ply"
    write_points_ply(path, points, binary=binary, comments=["colour by d\u00e9viation"])
    assert PlyData.read(str(path)).comments == ["written by skelcore", "colour by d\\xe9viation"]


def test_reads_and_writes_without_loading_plyfile():
    """The PLY code needs no plyfile at run time (a fresh interpreter in which it cannot be imported)."""
    code = ("import sys, tempfile, os\nsys.modules['plyfile'] = None\nimport numpy as np\n"
            "from skelcore.io import write_curve_ply, load_curve\nfrom skelcore.benchmark import read_reference\n"
            "d = tempfile.mkdtemp()\np = os.path.join(d, 'c.ply')\n"
            "write_curve_ply(p, np.eye(3), [[0, 1], [1, 2]], scalars={'radius': np.ones(3)})\n"
            "print(load_curve(p).n_edges, read_reference(p).radius.tolist())")  # fmt: skip
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=120)
    assert out.returncode == 0, out.stderr
    assert out.stdout.split("\n")[0] == "2 [1.0, 1.0, 1.0]"
