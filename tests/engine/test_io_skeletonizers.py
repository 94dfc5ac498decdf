"""Other tools' output formats, each from small files written here in that tool's format: PyGEL
.graph, PCL's binary_compressed PCD (LZF), LAS/LAZ (laspy extra), CGAL's correspondence polylines,
skeletal index files, kimimaro's voxel-coordinate SWC with --skeleton-scale/--skeleton-offset,
skeletor's SWC + mesh map, pc-skeletor's filtered contracted cloud."""

import json
import sys

import numpy as np
import pytest

from skelcore import evaluate, load_cloud, load_curve, shapes
from skelcore.cli import main
from skelcore.errors import SkelInputError
from skelcore.io import load_any, write_curve_ply, write_points_ply
from skelcore.io.lzf import lzf_decompress


def lzf_compress(data: bytes) -> bytes:
    """A small greedy LZF compressor (liblzf's token format), for writing test files."""
    out, lit, table, i, n = bytearray(), bytearray(), {}, 0, len(data)

    def flush():
        while lit:
            chunk = lit[:32]
            out.append(len(chunk) - 1)
            out.extend(chunk)
            del lit[:32]

    while i < n:
        if i + 2 < n:
            key = data[i:i + 3]
            ref = table.get(key)
            table[key] = i
            if ref is not None and i - ref - 1 < 8192:
                off, length = i - ref - 1, 3
                while i + length < n and length < 264 and data[ref + length] == data[i + length]:
                    length += 1
                flush()
                l2 = length - 2
                if l2 < 7:
                    out.append((l2 << 5) | (off >> 8))
                else:
                    out += bytes([(7 << 5) | (off >> 8), l2 - 7])
                out.append(off & 0xFF)
                i += length
                continue
        lit.append(data[i])
        i += 1
    flush()
    return bytes(out)


def run(*argv):
    return main([str(a) for a in argv])


# ---- LZF / PCD binary_compressed ----------------------------------------------------------------


def test_lzf_decompresses_liblzf_output():
    # produced by liblzf 3.6 (python-lzf's lzf.compress), overlapping back-references included
    raw = b"aaaaaaaaaaaaaaaaaaaaaabcabcabc" * 5
    packed = b"\x01aa\xe0\x0b\x00\x01bc\xa0\x02\xe0\x0c\x00\xe0W\x1d\x01bc"
    assert lzf_decompress(packed, len(raw)) == raw


@pytest.mark.parametrize("n", [1, 50, 5000])
def test_lzf_round_trip(n):
    rng = np.random.default_rng(n)
    raw = (np.round(rng.normal(size=n) * 4) / 4).astype(np.float32).tobytes() + b"xyz" * n
    assert lzf_decompress(lzf_compress(raw), len(raw)) == raw


def test_lzf_rejects_corrupt_data():
    with pytest.raises(ValueError):
        lzf_decompress(b"\x05ab", 6)  # literal run past the end
    with pytest.raises(ValueError):
        lzf_decompress(b"\x20\x05", 10)  # back-reference before the start


def _pcd_compressed(points: np.ndarray, padding: bool = False, corrupt: bool = False) -> bytes:
    n = len(points)
    rgb = np.arange(n, dtype=np.uint32)
    fields = "x y z rgb" + (" _" if padding else "")
    size = "4 4 4 4" + (" 4" if padding else "")
    typ = "F F F U" + (" U" if padding else "")
    count = "1 1 1 1" + (" 1" if padding else "")
    head = (f"# .PCD v0.7 - Point Cloud Data file format\nVERSION 0.7\nFIELDS {fields}\nSIZE {size}\n"
            f"TYPE {typ}\nCOUNT {count}\nWIDTH {n}\nHEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS {n}\n"
            "DATA binary_compressed\n").encode()
    p32 = points.astype(np.float32)
    # structure of arrays; PCL leaves the '_' padding out of the compressed block
    raw = p32[:, 0].tobytes() + p32[:, 1].tobytes() + p32[:, 2].tobytes() + rgb.tobytes()
    packed = lzf_compress(raw)
    if corrupt:
        packed = packed[: len(packed) // 2]
    return head + np.array([len(packed), len(raw)], dtype="<u4").tobytes() + packed


@pytest.mark.parametrize("padding", [False, True])
def test_pcd_binary_compressed_loads(tmp_path, padding):
    pts = shapes.cylinder(700, seed=1).cloud
    f = tmp_path / "c.pcd"
    f.write_bytes(_pcd_compressed(pts, padding=padding))
    assert np.allclose(load_cloud(f), pts.astype(np.float32))


def test_pcd_binary_compressed_corrupt_is_one_line(tmp_path):
    f = tmp_path / "c.pcd"
    data = bytearray(_pcd_compressed(shapes.cylinder(300, seed=1).cloud))
    f.write_bytes(bytes(data[: len(data) - 40]))
    with pytest.raises(SkelInputError, match="c.pcd: truncated") as info:
        load_cloud(f)
    assert "\n" not in str(info.value)


# ---- PyGEL .graph -------------------------------------------------------------------------------


def test_pygel_graph_loads_as_a_curve(tmp_path):
    f = tmp_path / "skel.graph"
    f.write_text("n 0 0 0 \nn 1 0 0 \nn 1 1 0.5 \nn 2 1 0.5 \nc 0 1\nc 1 2\nc 1 3\n")
    c = load_curve(f)
    assert c.n_vertices == 4 and c.edges.tolist() == [[0, 1], [1, 2], [1, 3]]
    assert load_any(f).kind == "curve"
    g = tmp_path / "noext"
    g.write_bytes(f.read_bytes())
    assert load_curve(g).n_edges == 3  # recognised by content


def test_pygel_graph_errors(tmp_path):
    f = tmp_path / "bad.graph"
    f.write_text("n 0 0 0\nn 1 0 0\nx 0 1\n")
    with pytest.raises(SkelInputError, match="bad.graph: line 3"):
        load_curve(f)
    f.write_text("n 0 0 0\nn 1 0 0\nc 0 5\n")
    with pytest.raises(SkelInputError, match="out of range"):
        load_curve(f)


# ---- LAS / LAZ ----------------------------------------------------------------------------------


def test_las_and_laz_load_through_laspy(tmp_path):
    laspy = pytest.importorskip("laspy")
    pts = shapes.cylinder(500, seed=2).cloud * 10 + 1000
    for suffix in ("las", "laz"):
        header = laspy.LasHeader(point_format=3, version="1.2")
        header.scales = np.array([0.001, 0.001, 0.001])
        header.offsets = pts.min(axis=0)
        las = laspy.LasData(header)
        las.x, las.y, las.z = pts[:, 0], pts[:, 1], pts[:, 2]
        f = tmp_path / f"c.{suffix}"
        las.write(str(f))
        assert np.allclose(load_cloud(f), pts, atol=1e-3)


def test_las_without_the_extra_names_it(tmp_path, monkeypatch):
    f = tmp_path / "c.las"
    f.write_bytes(b"LASF" + b"\0" * 300)
    monkeypatch.setitem(sys.modules, "laspy", None)  # import laspy raises ImportError
    with pytest.raises(SkelInputError, match=r"c.las: .*pip install 'skelscope\[las\]'"):
        load_cloud(f)


# ---- CGAL correspondence, skeletal index --------------------------------------------------------


@pytest.fixture(scope="module")
def cyl(tmp_path_factory):
    d = tmp_path_factory.mktemp("cyl")
    sh = shapes.cylinder(900, seed=3)
    write_points_ply(d / "cloud.ply", sh.cloud)
    return d, sh


def _json(path):
    return json.loads(path.read_text())


def test_cgal_correspondence_file_loads_as_skeletal_set_with_index(cyl, tmp_path):
    d, sh = cyl
    # CGAL writes, per skeleton vertex, one "2 skeleton_point surface_point" line per surface
    # vertex, with 6 significant digits; here the skeleton vertices are every 9th axis point
    nodes = np.unique(np.round(sh.skeletal[:, 2] * 2) / 2)
    owner = np.argmin(np.abs(sh.skeletal[:, 2][:, None] - nodes[None]), axis=1)
    order = np.random.default_rng(0).permutation(len(sh.cloud))
    lines = [
        "2 " + " ".join(f"{x:.6g}" for x in (0.0, 0.0, nodes[owner[i]], *sh.cloud[i])) for i in order
    ]
    f = tmp_path / "correspondance-poly.polylines.txt"
    f.write_text("\n".join(lines) + "\n")
    assert run("evaluate", d / "cloud.ply", "--skeletal", f, "--json", tmp_path / "o.json", "--quiet") == 0
    doc = _json(tmp_path / "o.json")
    assert doc["correspondence"] == "index" and doc["topology"] is not None
    pointwise = np.column_stack([np.zeros(len(owner)), np.zeros(len(owner)), nodes[owner]])
    # the surface points were matched back to their cloud rows (row order matters for ties)
    ref = evaluate(sh.cloud, pointwise[order], skeletal_index=order).summary()
    assert doc["centeredness"]["skeletal"] == pytest.approx(ref["centeredness"]["skeletal"])


def test_cgal_correspondence_with_another_cloud_is_one_line(cyl, tmp_path, capsys):
    d, sh = cyl
    f = tmp_path / "corr.polylines.txt"
    f.write_text("".join(f"2 0 0 {z:.6g} {x + 5:.6g} {y:.6g} {z:.6g}\n" for x, y, z in sh.cloud[:50]))
    assert run("evaluate", d / "cloud.ply", "--skeletal", f, "--quiet") == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "match no cloud point" in err and "corr.polylines.txt" in err


@pytest.mark.parametrize("kind", ["txt", "npy"])
def test_skeletal_index_file(cyl, tmp_path, kind):
    d, sh = cyl
    rows = np.arange(0, len(sh.cloud), 3)
    write_points_ply(tmp_path / "s.ply", sh.skeletal[rows])
    idx = tmp_path / f"i.{kind}"
    np.save(idx, rows) if kind == "npy" else np.savetxt(idx, rows, fmt="%d")
    assert run("evaluate", d / "cloud.ply", "--skeletal", tmp_path / "s.ply", "--skeletal-index", idx,
               "--json", tmp_path / "o.json", "--quiet") == 0
    assert _json(tmp_path / "o.json")["correspondence"] == "index"


@pytest.mark.parametrize(
    "content, message",
    [("0\n1\n", "has 2 rows, the skeletal set 300"), ("0\n" * 299 + "900\n", "cloud row 900 out of range"),
     ("0\n" * 299 + "1.5\n", "line 300: '1.5' is not a whole number")],
)
def test_skeletal_index_errors_are_one_line(cyl, tmp_path, capsys, content, message):
    d, sh = cyl
    write_points_ply(tmp_path / "s.ply", sh.skeletal[:300])
    (tmp_path / "i.txt").write_text(content)
    assert run("evaluate", d / "cloud.ply", "--skeletal", tmp_path / "s.ply", "--skeletal-index",
               tmp_path / "i.txt", "--quiet") == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and message in err and "i.txt" in err


# ---- kimimaro / skeletor / pc-skeletor ----------------------------------------------------------


def _swc(path, vertices, parents, radius=1.0):
    rows = [f"{i + 1} 0 {x:.6f} {y:.6f} {z:.6f} {radius} {p + 1 if p >= 0 else -1}"
            for i, ((x, y, z), p) in enumerate(zip(vertices, parents))]
    path.write_text("# id type x y z radius parent\n" + "\n".join(rows) + "\n")


def test_kimimaro_voxel_swc_needs_scale_and_offset(cyl, tmp_path, capsys):
    d, sh = cyl
    origin, voxel = np.array([-0.6, -0.6, -0.1]), 0.02
    vox = (sh.curve_vertices - origin) / voxel  # kimimaro writes voxel coordinates
    _swc(tmp_path / "k.swc", vox, np.arange(len(vox)) - 1)
    out = tmp_path / "o.json"
    assert run("evaluate", d / "cloud.ply", "--curve", tmp_path / "k.swc", "--json", out, "--quiet") == 0
    assert "frame" in [w["code"] for w in _json(out)["warnings"]]
    assert "warning [frame]" in capsys.readouterr().err
    assert run("evaluate", d / "cloud.ply", "--curve", tmp_path / "k.swc", "--json", out, "--quiet", "--strict",
               "--skeleton-scale", voxel, "--skeleton-offset", *origin) == 0
    ref = evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges)).summary()
    assert _json(out)["boundedness"]["curve"] == pytest.approx(ref["boundedness"]["curve"])


def test_skeletor_swc_with_mesh_map(cyl, tmp_path):
    d, sh = cyl
    # skeletor: skeleton.swc (nodes) and skeleton.mesh_map (node of every mesh vertex); the
    # pointwise skeletal set is nodes[mesh_map]
    nodes = sh.curve_vertices
    _swc(tmp_path / "s.swc", nodes, np.arange(len(nodes)) - 1)
    mesh_map = np.argmin(np.abs(sh.cloud[:, 2][:, None] - nodes[:, 2][None]), axis=1)
    curve = load_curve(tmp_path / "s.swc")
    np.save(tmp_path / "skel.npy", curve.vertices[mesh_map])
    out = tmp_path / "o.json"
    assert run("evaluate", d / "cloud.ply", "--skeletal", tmp_path / "skel.npy", "--curve", tmp_path / "s.swc",
               "--json", out, "--quiet", "--strict") == 0
    doc = _json(out)
    assert doc["correspondence"] == "pointwise" and doc["coverage"]["curve"]["fraction"] > 0.9


def test_pc_skeletor_filtered_contracted_cloud(cyl, tmp_path, capsys):
    d, sh = cyl
    # pc-skeletor's 01_point_cloud_contracted drops outliers: fewer rows than the cloud
    keep = np.random.default_rng(1).random(len(sh.cloud)) > 0.1
    write_points_ply(tmp_path / "01_point_cloud_contracted.ply", sh.skeletal[keep])
    write_curve_ply(tmp_path / "02_skeleton.ply", sh.curve_vertices, sh.curve_edges)  # Open3D LineSet PLY
    out = tmp_path / "o.json"
    args = ["evaluate", d / "cloud.ply", "--skeletal", tmp_path / "01_point_cloud_contracted.ply",
            "--curve", tmp_path / "02_skeleton.ply", "--json", out, "--quiet"]
    assert run(*args) == 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "--skeletal-index" in err[0] and "--correspondence reverse" in err[0]
    assert _json(out)["topology"] is None
    assert run(*args, "--correspondence", "reverse") == 0
    doc = _json(out)
    assert doc["correspondence"] == "reverse" and doc["topology"] is not None
    assert doc["centeredness"]["skeletal"] is not None
