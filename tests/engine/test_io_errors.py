"""Every kind of bad input gives a SkelInputError with one line that names the file."""

from __future__ import annotations

import os
import struct
import warnings
from pathlib import Path

import numpy as np
import pytest

from skelcore.errors import SkelInputError
from skelcore.io import load_any, load_cloud, load_curve, load_points


def _ply_binary_cloud(n: int = 5, *, count: int | None = None, cut: int = 0) -> bytes:
    head = f"ply\nformat binary_little_endian 1.0\nelement vertex {count if count is not None else n}\n"
    head += "property float x\nproperty float y\nproperty float z\nend_header\n"
    body = np.arange(3 * n, dtype="<f4").tobytes()
    return head.encode() + body[: len(body) - cut]


def _ply_curve(vertices: str, edges: list[tuple[int, int]], n_vertices: int) -> bytes:
    head = (
        f"ply\nformat ascii 1.0\nelement vertex {n_vertices}\nproperty double x\nproperty double y\n"
        f"property double z\nelement edge {len(edges)}\nproperty int vertex1\nproperty int vertex2\nend_header\n"
    )
    return (head + vertices + "".join(f"{a} {b}\n" for a, b in edges)).encode()


def _ply_lists(face: str, rows: bytes, *, fmt: str = "binary_little_endian", faces: int = 2) -> bytes:
    """A face element (the list property ``face``) before three float vertices (``rows`` then the
    vertices' bytes, or their text in ASCII)."""
    head = (f"ply\nformat {fmt} 1.0\nelement face {faces}\n{face}\nelement vertex 3\nproperty float x\n"
            "property float y\nproperty float z\nend_header\n")  # fmt: skip
    vertices = b"0 0 0\n1 0 0\n0 1 0\n" if fmt == "ascii" else np.eye(3, dtype="<f4").tobytes()
    return head.encode() + rows + vertices


def _ply_curve_props(edge_props: str, rows: bytes, edges: int = 1) -> bytes:
    """Two vertices (lines 10 and 11) and ``edges`` rows of an edge element with ``edge_props`` (from line 12)."""
    head = ("ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\nproperty float z\n"
            f"element edge {edges}\n{edge_props}\nend_header\n0 0 0\n1 0 0\n")  # fmt: skip
    return head.encode() + rows


TRIANGLE = struct.pack("<B3i", 3, 0, 1, 2)
FACE_LIST = "property list uchar int vertex_indices"


def _npy(arr: np.ndarray) -> bytes:
    import io

    buf = io.BytesIO()
    np.save(buf, arr)
    return buf.getvalue()


GOOD3 = "0 0 0\n1 0 0\n0 1 0\n"
CURVE_V = "0 0 0\n1 0 0\n2 0 0\n"

# (case id, file name, content, loader, expected words in the message)
CASES = [
    ("unknown_format", "cloud.foo", b"hello\nworld\n", load_cloud, "unknown file format"),
    ("empty_file", "cloud.xyz", b"", load_cloud, "empty"),
    ("whitespace_only", "cloud.xyz", b"  \n\n", load_cloud, "empty"),
    ("ply_truncated_binary", "c.ply", _ply_binary_cloud(cut=7), load_cloud, "truncated"),
    ("ply_count_too_big", "c.ply", _ply_binary_cloud(count=10**9), load_cloud, "truncated"),
    ("ply_no_end_header", "c.ply", b"ply\nformat ascii 1.0\nelement vertex 1\n", load_cloud, "end_header"),
    ("ply_ascii_short_row", "c.ply", b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
     b"property float z\nend_header\n1 2 3\n1 3\n", load_cloud, "line 9 has 2 columns"),  # fmt: skip
    ("ply_bad_property_type", "c.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty real x\nend_header\n1\n",
     load_cloud, "bad property line"),  # fmt: skip
    ("ply_bad_format", "c.ply", b"ply\nformat weird 1.0\nelement vertex 0\nend_header\n", load_cloud, "format"),
    ("ply_no_x", "c.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty float a\nproperty float y\n"
     b"property float z\nend_header\n1 2 3\n", load_cloud, "no x"),  # fmt: skip
    ("ply_no_vertex_element", "c.ply", b"ply\nformat ascii 1.0\nelement foo 1\nproperty float x\nend_header\n1\n",
     load_cloud, "no vertex element"),  # fmt: skip
    ("ply_text_garbage_row", "c.ply", b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
     b"property float z\nend_header\n1 2 3\n1 two 3\n", load_cloud, "line 9: 'two' is not a number"),  # fmt: skip
    ("ply_empty_cloud", "c.ply", _ply_binary_cloud(n=0), load_cloud, "0 points"),
    ("ply_inf", "c.ply", b"ply\nformat ascii 1.0\nelement vertex 2\nproperty float x\nproperty float y\n"
     b"property float z\nend_header\n1 2 3\n1 inf 3\n", load_cloud, "infinite"),  # fmt: skip
    ("ply_bad_element_count", "c.ply", b"ply\nformat ascii 1.0\nelement vertex -3\nend_header\n", load_cloud,
     "bad element line"),  # fmt: skip
    ("ply_crlf_missing_rows", "c.ply", b"ply\r\nformat ascii 1.0\r\nelement vertex 3\r\nproperty float x\r\n"
     b"property float y\r\nproperty float z\r\nend_header\r\n1 2 3\r\n", load_cloud, "more rows than the file has"),
    ("ply_big_endian_truncated", "c.ply", _ply_binary_cloud(cut=5).replace(b"little", b"big"), load_cloud, "truncated"),
    ("ply_list_row_past_end", "c.ply", _ply_lists(FACE_LIST, TRIANGLE + struct.pack("<B", 200)), load_cloud,
     "row 2 runs past the end"),  # fmt: skip
    ("ply_list_count_too_big", "c.ply", _ply_lists(FACE_LIST, TRIANGLE, faces=4 * 10**9), load_cloud, "truncated"),
    ("ply_list_length_too_big", "c.ply", _ply_lists("property list uint int vertex_indices",
     struct.pack("<I", 2**32 - 1), faces=1), load_cloud, "runs past the end"),  # fmt: skip
    ("ply_list_negative_length", "c.ply", _ply_lists("property list char int vertex_indices",
     struct.pack("<b3i", 3, 0, 1, 2) + struct.pack("<b", -1)), load_cloud, "row 2: negative length -1"),  # fmt: skip
    ("ply_list_unknown_type", "c.ply", _ply_lists("property list uchar real vertex_indices", b""), load_cloud,
     "unknown type 'real'"),  # fmt: skip
    ("ply_list_float_length", "c.ply", _ply_lists("property list float int vertex_indices", b""), load_cloud,
     "integer type"),  # fmt: skip
    ("ply_vertex_x_list", "c.ply", b"ply\nformat ascii 1.0\nelement vertex 1\nproperty list uchar float x\n"
     b"property float y\nproperty float z\nend_header\n1 0 0 0\n", load_cloud, "property x is a list"),  # fmt: skip
    ("xyz_header_only", "c.csv", b"x,y,z\n", load_cloud, "no rows"),
    ("xyz_nan", "c.xyz", b"0 0 0\n1 nan 0\n0 1 0\n", load_points, "NaN"),
    ("xyz_all_coincident", "c.xyz", b"1 2 3\n1 2 3\n1 2 3\n", load_cloud, "same position"),
    ("xyz_single_point", "c.xyz", b"1 2 3\n", load_cloud, "single point"),
    ("xyz_two_columns", "c.xyz", b"1 2\n3 4\n", load_cloud, "3 numbers"),
    ("xyz_short_row", "c.txt", b"1 2 3\n4 5 6\n7 8\n", load_cloud, "line 3 has 2 columns"),
    ("xyz_word_in_data", "c.txt", b"1 2 3\n4 five 6\n", load_cloud, "line 2"),
    ("pts_count_mismatch", "c.pts", b"5\n1 2 3\n4 5 6\n", load_cloud, "says 5 points"),
    ("pcd_compressed", "c.pcd", b"VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 2\n"
     b"HEIGHT 1\nPOINTS 2\nDATA binary_compressed\n\x00\x00", load_cloud, "binary_compressed"),  # fmt: skip
    ("pcd_truncated_binary", "c.pcd", b"VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\n"
     b"HEIGHT 1\nPOINTS 3\nDATA binary\n" + bytes(20), load_cloud, "truncated"),  # fmt: skip
    ("pcd_no_z", "c.pcd", b"VERSION .7\nFIELDS x y\nSIZE 4 4\nTYPE F F\nCOUNT 1 1\nWIDTH 1\nHEIGHT 1\n"
     b"POINTS 1\nDATA ascii\n1 2\n", load_cloud, "no z"),  # fmt: skip
    ("pcd_row_count", "c.pcd", b"VERSION .7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 3\n"
     b"HEIGHT 1\nPOINTS 3\nDATA ascii\n1 2 3\n4 5 6\n", load_cloud, "says 3 points"),  # fmt: skip
    ("npy_two_columns", "c.npy", _npy(np.zeros((4, 2))), load_cloud, "shape (4, 2)"),
    ("npy_truncated", "c.npy", _npy(np.arange(30.0).reshape(10, 3))[:-16], load_cloud, "truncated"),
    ("npy_strings", "c.npy", _npy(np.array([["a", "b", "c"]])), load_cloud, "not numbers"),
    ("npz_ambiguous", "c.npz", None, load_cloud, "cannot tell"),
    ("npz_not_zip", "c.npz", b"PK\x03\x04garbage", load_cloud, "malformed NPZ"),
    ("json_broken", "c.json", b'{"vertices": [[0, 0, 0], [1, 2', load_cloud, "malformed JSON"),
    ("json_no_vertices", "c.json", b'{"nodes_xyz": []}', load_cloud, "no 'vertices'"),
    ("json_strings", "c.json", b'{"vertices": [["a", 0, 0]]}', load_cloud, "number rows"),
    ("off_truncated", "c.off", b"OFF\n4 0 0\n0 0 0\n1 0 0\n", load_cloud, "truncated"),
    ("off_binary", "c.off", b"OFF BINARY\n\x00\x00", load_cloud, "binary OFF"),
    ("obj_bad_number", "c.obj", b"v 0 0 0\nv 1 x 0\n", load_cloud, "line 2"),
    # curves
    ("ply_edge_out_of_range", "s.ply", _ply_curve(CURVE_V, [(0, 1), (1, 3)], 3), load_curve, "out of range"),
    ("ply_edge_negative", "s.ply", _ply_curve(CURVE_V, [(0, -1)], 3), load_curve, "out of range"),
    ("ply_curve_inf", "s.ply", _ply_curve("0 0 0\n1 inf 0\n2 0 0\n", [(0, 1), (1, 2)], 3), load_curve, "inf"),
    ("ply_curve_all_nan", "s.ply", _ply_curve("nan 0 0\n1 nan 0\n", [(0, 1)], 2), load_curve, "no vertices"),
    ("curve_all_coincident", "s.ply", _ply_curve("1 1 1\n1 1 1\n", [(0, 1)], 2), load_curve, "same position"),
    ("ply_edge_pair_list", "s.ply", _ply_curve_props("property list uchar int vertex1\nproperty int vertex2",
     b"1 0 1\n"), load_curve, "property vertex1 is a list"),  # fmt: skip
    ("ply_edge_no_indices", "s.ply", _ply_curve_props("property float weight", b"0.5\n"), load_curve,
     "no vertex1/vertex2 properties (properties: weight)"),  # fmt: skip
    ("ply_ascii_list_short_row", "s.ply", _ply_curve_props(FACE_LIST, b"3 0 1 0\n3 0 1\n", edges=2), load_curve,
     "line 13 has 3 values, too few"),  # fmt: skip
    ("ply_ascii_list_long_row", "s.ply", _ply_curve_props(FACE_LIST, b"3 0 1 0\n2 0 1 0\n", edges=2), load_curve,
     "line 13 has 4 values, expected 3"),  # fmt: skip
    ("ply_ascii_list_bad_length", "s.ply", _ply_curve_props(FACE_LIST, b"3 0 1 0\n1.5 0 1\n", edges=2), load_curve,
     "line 13: list length '1.5'"),  # fmt: skip
    ("ply_ascii_list_word", "s.ply", _ply_curve_props(FACE_LIST, b"3 0 1 0\n3 0 one 1\n", edges=2), load_curve,
     "line 13: 'one' is not a number"),  # fmt: skip
    ("ply_polyline_fractional_index", "s.ply", _ply_curve_props(FACE_LIST, b"2 0 0.5\n"), load_curve,
     "whole numbers"),  # fmt: skip
    ("obj_line_index_out_of_range", "s.obj", b"v 0 0 0\nv 1 0 0\nl 1 9\n", load_curve, "line 3: vertex index 9"),
    ("obj_line_negative_too_far", "s.obj", b"v 0 0 0\nv 1 0 0\nl 1 -3\n", load_curve, "vertex index -3"),
    ("obj_line_index_zero", "s.obj", b"v 0 0 0\nv 1 0 0\nl 0 1\n", load_curve, "index 0"),
    ("obj_no_lines_as_curve", "s.obj", b"v 0 0 0\nv 1 0 0\n", load_curve, "no edges"),
    ("xyz_as_curve", "s.xyz", GOOD3.encode(), load_curve, "no edges"),
    ("cg_count_mismatch", "s.cg", b"# D:3 NV:3 NE:2\nv 0 0 0\nv 1 0 0\ne 1 2\n", load_curve, "NV:3 NE:2"),
    ("cg_index_out_of_range", "s.cg", b"# D:3 NV:2 NE:1\nv 0 0 0\nv 1 0 0\ne 1 5\n", load_curve, "index 5 out"),
    ("cg_2d", "s.cg", b"# D:2 NV:1 NE:0\nv 0 0\n", load_curve, "D:2"),
    ("cg_bad_line", "s.cg", b"# D:3 NV:1 NE:0\nv 0 0 0\nx 1\n", load_curve, "line 3"),
    ("swc_missing_parent", "s.swc", b"1 1 0 0 0 1 -1\n2 3 1 0 0 1 7\n", load_curve, "parent 7"),
    ("swc_duplicate_id", "s.swc", b"1 1 0 0 0 1 -1\n1 3 1 0 0 1 -1\n", load_curve, "more than once"),
    ("swc_six_columns", "s.swc", b"1 1 0 0 0 -1\n", load_curve, "expected at least 7"),
    ("polylines_count_mismatch", "s.polylines.txt", b"3 0 0 0 1 0 0\n", load_curve, "says 3 points"),
    ("json_curve_bad_edges", "s.json", b'{"vertices": [[0,0,0],[1,0,0]], "edges": [[0, 1, 2]]}', load_curve,
     "pairs"),  # fmt: skip
    ("json_curve_fractional_edge", "s.json", b'{"vertices": [[0,0,0],[1,0,0]], "edges": [[0, 0.5]]}',
     load_curve, "whole numbers"),  # fmt: skip
]


def _write_case(tmp_path: Path, name: str, content: bytes | None, case_id: str) -> Path:
    path = tmp_path / name
    if case_id == "npz_ambiguous":
        np.savez(path, a=np.zeros((3, 3)), b=np.ones((3, 3)))
    else:
        path.write_bytes(content)
    return path


def _assert_one_line_naming(err: SkelInputError, path: Path) -> None:
    msg = str(err)
    assert "\n" not in msg
    assert path.name in msg
    assert err.path == str(path)


@pytest.mark.parametrize("case_id,name,content,loader,words", CASES, ids=[c[0] for c in CASES])
def test_bad_input_raises_one_line_naming_the_file(tmp_path, case_id, name, content, loader, words):
    path = _write_case(tmp_path, name, content, case_id)
    with pytest.raises(SkelInputError) as info, warnings.catch_warnings():
        warnings.simplefilter("ignore")  # ply_curve_all_nan warns about each dropped vertex first
        loader(path)
    _assert_one_line_naming(info.value, path)
    assert words in str(info.value)
    # load_any must fail the same way (it is what the viewer calls on a dropped file).
    if loader is not load_curve or case_id not in ("obj_no_lines_as_curve", "xyz_as_curve"):
        with pytest.raises(SkelInputError), warnings.catch_warnings():
            warnings.simplefilter("ignore")
            load_any(path)


@pytest.mark.parametrize("case_id", ["ply_count_too_big", "ply_list_count_too_big", "ply_list_length_too_big",
                                     "ply_list_row_past_end"])  # fmt: skip
def test_ply_counts_beyond_the_file_allocate_nothing(tmp_path, case_id):
    """A count or list length larger than the file is refused before memory is taken for it."""
    import tracemalloc

    _, name, content, loader, _ = next(c for c in CASES if c[0] == case_id)
    path = _write_case(tmp_path, name, content, case_id)
    tracemalloc.start()
    try:
        with pytest.raises(SkelInputError, match="truncated"):
            loader(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 1_000_000


def test_missing_file(tmp_path):
    path = tmp_path / "nope.ply"
    with pytest.raises(SkelInputError, match="not found") as info:
        load_cloud(path)
    _assert_one_line_naming(info.value, path)


def test_folder_instead_of_file(tmp_path):
    path = tmp_path / "folder.ply"
    path.mkdir()
    with pytest.raises(SkelInputError, match="folder") as info:
        load_curve(path)
    _assert_one_line_naming(info.value, path)


@pytest.mark.skipif(not hasattr(os, "geteuid") or os.geteuid() == 0, reason="root can read any file")
def test_unreadable_file(tmp_path):
    path = tmp_path / "secret.xyz"
    path.write_text(GOOD3)
    path.chmod(0)
    try:
        with pytest.raises(SkelInputError, match="permission") as info:
            load_cloud(path)
        _assert_one_line_naming(info.value, path)
    finally:
        path.chmod(0o644)


def test_unreadable_file_reported_when_open_fails(tmp_path, monkeypatch):
    """Same as above but independent of the user running the tests (root reads everything)."""
    path = tmp_path / "secret.xyz"
    path.write_text(GOOD3)

    def deny(self):
        raise PermissionError(13, "Permission denied", str(self))

    monkeypatch.setattr(Path, "read_bytes", deny)
    with pytest.raises(SkelInputError, match="permission") as info:
        load_cloud(path)
    _assert_one_line_naming(info.value, path)


def test_open3d_lineset_with_edge_past_the_end_is_an_error(tmp_path):
    head = (
        "ply\nformat binary_little_endian 1.0\ncomment Created by Open3D\nelement vertex 2\n"
        "property double x\nproperty double y\nproperty double z\nelement edge 1\n"
        "property int vertex1\nproperty int vertex2\nend_header\n"
    )
    body = struct.pack("<6d", 0, 0, 0, 1, 0, 0) + struct.pack("<ii", 0, 2)
    path = tmp_path / "03_topology_LBC.ply"
    path.write_bytes(head.encode() + body)
    with pytest.raises(SkelInputError, match="edge index 2 out of range for 2 vertices"):
        load_curve(path)
