"""Round trips for every input format: write a generated cloud or curve with a small test-only
writer (the project has writers only for PLY/XYZ/NPY), load it back, compare.

The writers here are reused by test_io_fuzz.py (``CLOUD_WRITERS``, ``CURVE_WRITERS``).
"""

from __future__ import annotations

import json
import struct
from pathlib import Path

import numpy as np
import pytest
from plyfile import PlyData, PlyElement

from skelcore.io import detect_format, load_any, load_cloud, load_curve, load_points

# ---- generated inputs ----------------------------------------------------------------------------


def make_cloud(n: int = 40, seed: int = 3) -> np.ndarray:
    rng = np.random.default_rng(seed)
    # Values that are exact in float32 and in short decimal text keep comparisons exact.
    return np.round(rng.uniform(-50, 50, size=(n, 3)), 3)


# A Y-shaped tree: trunk 0-1-2-3, branch 2-4-5, branch 1-6-7 (as polylines for the CGAL format).
CURVE_BRANCHES = [[0, 1, 2, 3], [2, 4, 5], [1, 6, 7]]


def make_curve() -> tuple[np.ndarray, np.ndarray]:
    rng = np.random.default_rng(7)
    v = np.round(rng.uniform(-5, 5, size=(8, 3)), 3)
    e = np.array([(a, b) for br in CURVE_BRANCHES for a, b in zip(br[:-1], br[1:])], dtype=np.int64)
    return v, e


def edge_set(vertices: np.ndarray, edges: np.ndarray) -> set[frozenset]:
    """Edges as unordered pairs of coordinates: equal for the same graph whatever the vertex order."""
    return {frozenset((tuple(vertices[i]), tuple(vertices[j]))) for i, j in edges}


# ---- test-only writers: clouds --------------------------------------------------------------------


def _ply(path: Path, pts: np.ndarray, *, text: bool, byte_order: str = "<", dtype: str = "f8",
         extra: bool = False) -> None:  # fmt: skip
    fields = [("x", dtype), ("y", dtype), ("z", dtype)]
    if extra:
        fields += [("nx", "f4"), ("red", "u1"), ("green", "u1"), ("blue", "u1"), ("intensity", "i2")]
    a = np.zeros(len(pts), dtype=fields)
    a["x"], a["y"], a["z"] = pts.T
    PlyData([PlyElement.describe(a, "vertex")], text=text, byte_order=byte_order).write(str(path))


def write_ply_ascii(path, pts):
    _ply(path, pts, text=True, extra=True)


def write_ply_le_float(path, pts):
    _ply(path, pts, text=False, byte_order="<", dtype="f4")


def write_ply_be_double(path, pts):
    _ply(path, pts, text=False, byte_order=">", dtype="f8", extra=True)


def write_ply_le_int(path, pts):
    _ply(path, pts, text=False, byte_order="<", dtype="i4")


def write_open3d_pointcloud(path, pts):
    """Byte layout of Open3D's ``write_point_cloud`` (rply, binary little endian; double normals and
    uchar colours), as pc-skeletor writes ``01_point_cloud_contracted_*.ply`` and ``02_skeleton_*.ply``."""
    head = (
        "ply\nformat binary_little_endian 1.0\ncomment Created by Open3D\n"
        f"element vertex {len(pts)}\nproperty double x\nproperty double y\nproperty double z\n"
        "property double nx\nproperty double ny\nproperty double nz\n"
        "property uchar red\nproperty uchar green\nproperty uchar blue\nend_header\n"
    )
    body = b"".join(struct.pack("<6d3B", *p, 0.0, 0.0, 1.0, 0, 0, 255) for p in pts.tolist())
    Path(path).write_bytes(head.encode() + body)


def write_pcd_ascii(path, pts):
    head = (
        "# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS x y z rgb\nSIZE 4 4 4 4\n"
        f"TYPE F F F U\nCOUNT 1 1 1 1\nWIDTH {len(pts)}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\n"
        f"POINTS {len(pts)}\nDATA ascii\n"
    )
    body = "".join(f"{x:.9g} {y:.9g} {z:.9g} 4294967295\n" for x, y, z in pts.tolist())
    Path(path).write_text(head + body)


def write_pcd_binary(path, pts):
    # Padding field "_" and a 3-count normal field as PCL writes them; x y z after them.
    n = len(pts)
    rec = np.zeros(n, dtype=[("pad", "<u1", (4,)), ("normal", "<f4", (3,)), ("x", "<f4"), ("y", "<f4"),
                             ("z", "<f4"), ("label", "<u2")])  # fmt: skip
    rec["x"], rec["y"], rec["z"] = pts.T
    head = (
        "VERSION .7\nFIELDS _ normal x y z label\nSIZE 1 4 4 4 4 2\nTYPE U F F F F U\nCOUNT 4 3 1 1 1 1\n"
        f"WIDTH {n}\nHEIGHT 1\nPOINTS {n}\nDATA binary\n"
    )
    Path(path).write_bytes(head.encode() + rec.tobytes())


def write_xyz_space(path, pts):
    Path(path).write_text("".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in pts.tolist()))


def write_csv_header(path, pts):
    lines = ["x,y,z,intensity,label"] + [f"{x!r},{y!r},{z!r},0.5,leaf" for x, y, z in pts.tolist()]
    Path(path).write_text("\n".join(lines) + "\n")


def write_txt_tabs_comments(path, pts):
    body = "".join(f"{x!r}\t{y!r}\t{z!r}\t1\t2\n" for x, y, z in pts.tolist())
    Path(path).write_text("# exported by a scanner\n// units: mm\n\n" + body, encoding="utf-8")


def write_pts_count(path, pts):
    body = "".join(f"{x:.3f} {y:.3f} {z:.3f} -1200 255 128 0\n" for x, y, z in pts.tolist())
    Path(path).write_text(f"{len(pts)}\n" + body)


def write_obj_vertices(path, pts):
    body = "".join(f"v {x!r} {y!r} {z!r} 0.1 0.2 0.3\n" for x, y, z in pts.tolist())
    Path(path).write_text("# cloud\no cloud\n" + body + "vn 0 0 1\nf 1 2 3\n")


def write_off(path, pts):
    body = "".join(f"{x!r} {y!r} {z!r}\n" for x, y, z in pts.tolist())
    Path(path).write_text(f"OFF\n# comment\n{len(pts)} 1 0\n" + body + "3 0 1 2\n")


def write_npy(path, pts):
    np.save(path, pts)


def write_npy_float32_wide(path, pts):
    np.save(path, np.column_stack([pts, np.ones(len(pts))]).astype(np.float32))


def write_npz_cloud_key(path, pts):
    np.savez(path, cloud=pts, normals=np.zeros_like(pts))


def write_npz_only_array(path, pts):
    np.savez_compressed(path, whatever=pts)


def write_json_list(path, pts):
    Path(path).write_text(json.dumps(pts.tolist()))


# (suffix, writer); suffix may be a misleading one to pin content detection.
CLOUD_WRITERS = {
    "ply_ascii": (".ply", write_ply_ascii),
    "ply_le_float": (".ply", write_ply_le_float),
    "ply_be_double": (".ply", write_ply_be_double),
    "ply_le_int": (".ply", write_ply_le_int),
    "ply_named_txt": (".txt", write_ply_le_float),
    "open3d_pointcloud": (".ply", write_open3d_pointcloud),
    "pcd_ascii": (".pcd", write_pcd_ascii),
    "pcd_binary": (".pcd", write_pcd_binary),
    "xyz": (".xyz", write_xyz_space),
    "csv_header": (".csv", write_csv_header),
    "txt_tabs": (".txt", write_txt_tabs_comments),
    "pts_count": (".pts", write_pts_count),
    "obj": (".obj", write_obj_vertices),
    "off": (".off", write_off),
    "npy": (".npy", write_npy),
    "npy_f32_4col": (".npy", write_npy_float32_wide),
    "npz_cloud": (".npz", write_npz_cloud_key),
    "npz_single": (".npz", write_npz_only_array),
    "json": (".json", write_json_list),
}

# ---- test-only writers: curves --------------------------------------------------------------------


def write_open3d_lineset(path, v, e, *, colors: bool = False):
    """Byte layout of Open3D's ``write_line_set`` (rply, binary little endian), as pc-skeletor's
    ``export_results`` writes ``03_topology_*.ply``."""
    head = (
        "ply\nformat binary_little_endian 1.0\ncomment Created by Open3D\n"
        f"element vertex {len(v)}\nproperty double x\nproperty double y\nproperty double z\n"
        f"element edge {len(e)}\nproperty int vertex1\nproperty int vertex2\n"
    )
    if colors:
        head += "property uchar red\nproperty uchar green\nproperty uchar blue\n"
    head += "end_header\n"
    body = b"".join(struct.pack("<ddd", *p) for p in v)
    body += b"".join(struct.pack("<ii", int(a), int(b)) + (b"\x00\x00\xff" if colors else b"") for a, b in e)
    Path(path).write_bytes(head.encode() + body)


def write_open3d_lineset_colored(path, v, e):
    write_open3d_lineset(path, v, e, colors=True)


def write_ply_edge_ascii(path, v, e):
    vert = np.zeros(len(v), dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    vert["x"], vert["y"], vert["z"] = v.T
    edge = np.zeros(len(e), dtype=[("vertex1", "i4"), ("vertex2", "i4")])
    edge["vertex1"], edge["vertex2"] = e.T
    PlyData([PlyElement.describe(vert, "vertex"), PlyElement.describe(edge, "edge")], text=True).write(str(path))


def write_obj_lines(path, v, e):
    """Polylines with a negative (relative) index and v/vt tokens."""
    lines = ["# skeleton", "o skel"] + [f"v {x!r} {y!r} {z!r}" for x, y, z in v.tolist()]
    lines.append("l 1 2/1 3 4")  # trunk, one v/vt token
    lines.append("l 3 5 -3")  # -3 = vertex 6 of 8 (0-based 5)
    lines.append("l 2 7 8")
    Path(path).write_text("\n".join(lines) + "\n")


def write_cg(path, v, e, *, base: int = 1):
    lines = [f"# D:3 NV:{len(v)} NE:{len(e)}"]
    lines += [f"v {x!r} {y!r} {z!r}" for x, y, z in v.tolist()]
    lines += [f"e {a + base} {b + base}" for a, b in e]
    Path(path).write_text("\n".join(lines) + "\n")


def write_cg_zero_based(path, v, e):
    write_cg(path, v, e, base=0)


def write_swc(path, v, e):
    """Non-contiguous ids, rows shuffled, root first listed last; parent = the lower-index end."""
    ids = np.array([10, 20, 35, 40, 51, 60, 77, 90])
    parent = {b: a for a, b in e}  # the curve is a tree rooted at vertex 0
    rows = []
    for i in [3, 1, 7, 5, 2, 4, 6, 0]:
        p = ids[parent[i]] if i in parent else -1
        rows.append(f"{ids[i]} 3 {float(v[i, 0])!r} {float(v[i, 1])!r} {float(v[i, 2])!r} 0.5 {p}")
    Path(path).write_text("# SWC test\n# id type x y z r parent\n" + "\n".join(rows) + "\n")


def write_polylines(path, v, e):
    lines = [" ".join([str(len(br))] + [repr(float(c)) for i in br for c in v[i]]) for br in CURVE_BRANCHES]
    Path(path).write_text("\n".join(lines) + "\n")


def write_json_curve(path, v, e):
    Path(path).write_text(json.dumps({"vertices": v.tolist(), "edges": e.tolist()}))


def write_npz_curve(path, v, e):
    np.savez(path, vertices=v, edges=e)


CURVE_WRITERS = {
    "open3d_lineset": (".ply", write_open3d_lineset),
    "open3d_lineset_colored": (".ply", write_open3d_lineset_colored),
    "ply_edge_ascii": (".ply", write_ply_edge_ascii),
    "obj_lines": (".obj", write_obj_lines),
    "cg": (".cg", write_cg),
    "cg_zero_based": (".cg", write_cg_zero_based),
    "swc": (".swc", write_swc),
    "polylines": (".polylines.txt", write_polylines),
    "json_curve": (".json", write_json_curve),
    "npz_curve": (".npz", write_npz_curve),
}


# ---- tests ----------------------------------------------------------------------------------------


@pytest.mark.parametrize("name", sorted(CLOUD_WRITERS))
def test_cloud_format_round_trips(tmp_path, name):
    suffix, writer = CLOUD_WRITERS[name]
    pts = make_cloud()
    path = tmp_path / f"cloud{suffix}"
    writer(path, pts)
    got = load_cloud(path)
    assert got.dtype == np.float64 and got.shape == pts.shape
    if name == "ply_le_int":
        np.testing.assert_array_equal(got, np.trunc(pts))
    else:
        # float32 storage (PLY float, PCD, NPY f32) loses digits beyond ~1e-7 relative.
        np.testing.assert_allclose(got, pts, rtol=1e-6, atol=1e-4)
    loaded = load_any(path)
    assert loaded.kind == "points" and loaded.path == str(path)
    np.testing.assert_array_equal(loaded.points, got)
    np.testing.assert_array_equal(load_points(path), got)


@pytest.mark.parametrize("name", sorted(CURVE_WRITERS))
def test_curve_format_round_trips(tmp_path, name):
    suffix, writer = CURVE_WRITERS[name]
    v, e = make_curve()
    path = tmp_path / f"skel{suffix}"
    writer(path, v, e)
    curve = load_curve(path)
    assert curve.vertices.dtype == np.float64
    assert curve.n_vertices == len(v) and curve.n_edges == len(e)
    got_v = curve.vertices.astype(np.float32).astype(np.float64) if name == "ply_edge_ascii" else curve.vertices
    want_v = v.astype(np.float32).astype(np.float64) if name == "ply_edge_ascii" else v
    assert edge_set(got_v, curve.edges) == edge_set(want_v, e)
    loaded = load_any(path)
    assert loaded.kind == "curve" and loaded.curve is not None and loaded.curve.n_edges == len(e)


def test_ply_with_dot_txt_suffix_is_detected_as_ply(tmp_path):
    path = tmp_path / "really_a_ply.txt"
    write_ply_le_float(path, make_cloud())
    assert detect_format(path, path.read_bytes()[:64]) == "ply"


def test_obj_content_with_txt_suffix_is_detected_as_obj(tmp_path):
    v, e = make_curve()
    path = tmp_path / "skeleton.txt"
    write_obj_lines(path, v, e)
    assert load_any(path).kind == "curve"


def test_obj_polyline_gives_consecutive_edges_and_relative_indices(tmp_path):
    path = tmp_path / "p.obj"
    path.write_text("v 0 0 0\nv 1 0 0\nv 2 0 0\nv 3 1 0\nl 1 2 3 4\nl -1 -4\n")
    curve = load_curve(path)
    assert {tuple(r) for r in curve.edges.tolist()} == {(0, 1), (1, 2), (2, 3), (0, 3)}


def test_cg_with_radius_column_and_max_index_nv_is_one_based(tmp_path):
    path = tmp_path / "r.cg"
    path.write_text("# D:3 NV:3 NE:2\nv 0 0 0 0.1\nv 1 0 0 0.1\nv 2 0 0 0.1\ne 1 2\ne 2 3\n")
    assert load_curve(path).edges.tolist() == [[0, 1], [1, 2]]


def test_polylines_merge_shared_vertices_exactly(tmp_path):
    path = tmp_path / "s.polylines.txt"
    path.write_text("3 0 0 0 1 0 0 2 0 0\n2 1 0 0 1 1 0\n2 -0.0 0 0 0 0 -1\n")
    curve = load_curve(path)
    assert curve.n_vertices == 5  # (0,0,0) appears three times (once as -0.0), (1,0,0) twice
    assert curve.n_edges == 4
    assert curve.degrees().tolist() == [2, 3, 1, 1, 1]


def test_swc_roots_have_no_edge_and_ids_may_skip(tmp_path):
    path = tmp_path / "n.swc"
    path.write_text("1 1 0 0 0 1 -1\n5 3 0 0 1 1 1\n9 3 0 0 2 1 5\n12 1 5 5 5 1 -1\n13 3 5 5 6 1 12\n")
    curve = load_curve(path)
    assert curve.n_vertices == 5
    assert edge_set(curve.vertices, curve.edges) == {
        frozenset({(0.0, 0.0, 0.0), (0.0, 0.0, 1.0)}),
        frozenset({(0.0, 0.0, 1.0), (0.0, 0.0, 2.0)}),
        frozenset({(5.0, 5.0, 5.0), (5.0, 5.0, 6.0)}),
    }


def test_curve_nan_vertex_is_dropped_with_a_warning(tmp_path):
    v, e = make_curve()
    v[7] = np.nan  # pc-skeletor emits these
    path = tmp_path / "nan.ply"
    write_open3d_lineset(path, v, e)
    with pytest.warns(UserWarning, match="NaN"):
        curve = load_curve(path)
    assert curve.n_vertices == 7 and curve.n_edges == len(e) - 1


def test_mesh_ply_faces_load_as_points(tmp_path):
    pts = make_cloud(10)
    vert = np.zeros(10, dtype=[("x", "f4"), ("y", "f4"), ("z", "f4")])
    vert["x"], vert["y"], vert["z"] = pts.T
    face = np.array([([0, 1, 2],), ([2, 3, 4],)], dtype=[("vertex_indices", "i4", (3,))])
    PlyData([PlyElement.describe(vert, "vertex"), PlyElement.describe(face, "face")]).write(str(tmp_path / "m.ply"))
    loaded = load_any(tmp_path / "m.ply")
    assert loaded.kind == "points" and loaded.points.shape == (10, 3)


def test_loaded_inputs_are_protected_from_writers(tmp_path):
    from skelcore.errors import SkelInputError
    from skelcore.io import write_points_ply

    path = tmp_path / "in.xyz"
    write_xyz_space(path, make_cloud())
    pts = load_cloud(path)
    before = path.read_bytes()
    with pytest.raises(SkelInputError, match="overwrite"):
        write_points_ply(path, pts)
    assert path.read_bytes() == before


def test_real_hammer_cloud_loads_in_file_units(scans):
    pts = load_cloud(scans / "hammer_4096.ply")
    assert pts.shape == (4096, 3) and pts.dtype == np.float64
    np.testing.assert_allclose(pts[0], [-7.67962217330932617, -185.189102172851562, -13.0556678771972656], rtol=1e-7)


@pytest.mark.parametrize("text", [False, True])
def test_ply_list_layouts_load(tmp_path, text):
    """A list element before the vertices, and edges stored as polylines in a list property."""
    v, e = make_curve()
    face = np.array([([0, 1, 2],)], dtype=[("vertex_indices", "i4", (3,))])
    vert = np.zeros(len(v), dtype=[("x", "f8"), ("y", "f8"), ("z", "f8")])
    vert["x"], vert["y"], vert["z"] = v.T
    lines = np.empty(len(CURVE_BRANCHES), dtype=[("vertex_indices", object)])
    lines["vertex_indices"] = [np.array(b, dtype=np.int32) for b in CURVE_BRANCHES]
    elements = [PlyElement.describe(face, "face"), PlyElement.describe(vert, "vertex"),
                PlyElement.describe(lines, "edge", len_types={"vertex_indices": "u1"},
                                    val_types={"vertex_indices": "i4"})]  # fmt: skip
    path = tmp_path / "mixed.ply"
    PlyData(elements, text=text).write(str(path))
    curve = load_curve(path)
    assert edge_set(curve.vertices, curve.edges) == edge_set(v, e)
