"""The command line's refusals of bad inputs, as a user meets them (docs/guide/cli.md, "Exit codes"): one
line naming the file at fault and the problem, exit 2, nothing written. A repair refused for a curve
in another frame says how to map it, and ``skelcore convert --skeleton-scale/--skeleton-offset``
does the mapping; a curve whose every edge touches a NaN vertex is no curve; a binary_compressed PCD
promising more data than LZF can expand its bytes to is refused before anything is allocated."""

from __future__ import annotations

import struct

import numpy as np
import pytest

from skelcore import SkelInputError, shapes
from skelcore.cli import main
from skelcore.io import load_cloud, load_curve, write_curve_ply, write_points_ply
from skelcore.io.lzf import lzf_decompress

SCALE, OFFSET = 100.0, np.array([500.0, -300.0, 40.0])


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    d = tmp_path_factory.mktemp("refusals")
    s = shapes.cylinder(1500, seed=4)
    write_points_ply(d / "cloud.ply", s.cloud)
    write_curve_ply(d / "axis.ply", s.curve_vertices, s.curve_edges)
    write_curve_ply(d / "far.ply", s.curve_vertices * SCALE + OFFSET, s.curve_edges)
    v = np.repeat(s.cloud[:600:2] * 0.9, 2, axis=0)
    v[1::2] += 0.01
    write_curve_ply(d / "bits.ply", v, np.arange(len(v)).reshape(-1, 2))  # 300 two-vertex pieces
    return d


def _refused(argv: list[str], capsys) -> str:
    code = main(argv)
    err = capsys.readouterr().err
    assert code == 2 and err.count("\n") == 1 and "Traceback" not in err, err
    return err


@pytest.mark.parametrize("curve, says", [("far.ply", "another frame"), ("bits.ply", "300 components")])
def test_a_refused_repair_names_the_curve(files, capsys, curve, says):
    d = files
    err = _refused(["repair", str(d / "cloud.ply"), "--curve", str(d / curve), "--out-curve", str(d / "x.ply"),
                    "--quiet"], capsys)
    assert says in err and str(d / curve) in err
    assert not (d / "x.ply").exists()


def test_a_curve_in_another_frame_is_mapped_by_convert_as_the_refusal_says(files, capsys):
    d = files
    err = _refused(["repair", str(d / "cloud.ply"), "--curve", str(d / "far.ply"), "--out-curve",
                    str(d / "x.ply"), "--quiet"], capsys)
    assert "skelcore convert" in err and "--skeleton-scale" in err  # a command that takes those flags
    out = d / "mapped.ply"
    assert main(["convert", str(d / "far.ply"), str(out), "--skeleton-scale", str(1 / SCALE),
                 "--skeleton-offset", *(str(-x / SCALE) for x in OFFSET)]) == 0
    said = capsys.readouterr().out
    assert "mapped" in said and "read back: the same" in said
    np.testing.assert_allclose(load_curve(out).vertices, load_curve(d / "axis.ply").vertices, atol=1e-9)
    points = d / "mapped_points.ply"
    assert main(["convert", str(d / "far.ply"), str(points), "--as", "points", "--skeleton-scale", "2"]) == 0
    np.testing.assert_allclose(load_cloud(points), 2 * load_curve(d / "far.ply").vertices, rtol=1e-12)


def test_convert_refuses_a_bad_map_in_one_line(files, capsys):
    d = files
    err = _refused(["convert", str(d / "axis.ply"), str(d / "y.ply"), "--skeleton-scale", "0"], capsys)
    assert "--skeleton-scale" in err
    assert not (d / "y.ply").exists()


def test_a_curve_with_no_edge_left_after_its_nan_vertices_is_refused(files, capsys):
    d = files
    path = d / "nan_middle.ply"
    path.write_text("ply\nformat ascii 1.0\nelement vertex 3\nproperty float x\nproperty float y\nproperty float z\n"
                    "element edge 2\nproperty int vertex1\nproperty int vertex2\nend_header\n"
                    "0 0 1\nnan 0 2\n0 0 3\n0 1\n1 2\n")
    err = _refused(["evaluate", str(d / "cloud.ply"), "--curve", str(path), "--quiet"], capsys)
    assert str(path) in err and "NaN" in err and "nan " not in err and "warning" not in err


def test_lzf_refuses_an_output_its_input_cannot_expand_to(tmp_path):
    # a back-reference token of 3 bytes yields at most 264 bytes: 10 bytes cannot become 1.2 GB, and the
    # refusal comes before the output buffer is allocated (a 150-byte file must not cost 1.2 GB)
    with pytest.raises(ValueError, match="cannot expand"):
        lzf_decompress(b"\x00" * 10, 1_200_000_000)
    data = b"\x02abc" + bytes([0xE0, 0xFF, 0x02])  # 3 literals, then one reference copying 264 bytes
    assert lzf_decompress(data, 3 + 264) == b"abc" * 89
    pcd = (b"# .PCD v0.7\nVERSION 0.7\nFIELDS x y z\nSIZE 4 4 4\nTYPE F F F\nCOUNT 1 1 1\nWIDTH 100000000\n"
           b"HEIGHT 1\nVIEWPOINT 0 0 0 1 0 0 0\nPOINTS 100000000\nDATA binary_compressed\n"
           + struct.pack("<II", 10, 1_200_000_000) + b"\x00" * 10)
    path = tmp_path / "bomb.pcd"
    path.write_bytes(pcd)
    with pytest.raises(SkelInputError, match="cannot expand"):
        load_cloud(path)


@pytest.mark.parametrize("offset", [("nan", "0", "0"), ("0", "inf", "0")])
def test_evaluate_refuses_an_offset_that_is_not_finite_before_loading(files, capsys, offset):
    d = files
    err = _refused(["evaluate", str(d / "cloud.ply"), "--curve", str(d / "axis.ply"), "--skeleton-offset", *offset,
                    "--quiet"], capsys)
    assert "--skeleton-offset" in err and "finite" in err


@pytest.mark.parametrize("skeletal, curve, says", [
    ("same.ply", "same.ply", "another output names"),
    ("s.ply", "c.xyz", "no curve writer for .xyz"),
    ("s.swcx", "c.ply", "no point-set writer for .swcx"),
])
def test_skeletonize_refuses_outputs_it_cannot_write_as_named(files, capsys, skeletal, curve, says):
    d = files
    err = _refused(["skeletonize", str(d / "cloud.ply"), "--out-skeletal", str(d / skeletal), "--out-curve",
                    str(d / curve), "--raw", "--quiet"], capsys)
    assert says in err
    assert not (d / skeletal).exists() and not (d / curve).exists()


def test_skeletonize_writes_each_output_in_its_extensions_format(files, capsys):
    d = files
    assert main(["skeletonize", str(d / "cloud.ply"), "--out-skeletal", str(d / "sk.npy"), "--out-curve",
                 str(d / "cu.json"), "--raw", "--quiet"]) == 0
    assert np.load(d / "sk.npy").shape == (1500, 3)
    assert load_curve(d / "cu.json").n_edges > 0


def test_repair_refuses_a_format_that_would_lose_the_repaired_curve(tmp_path, capsys):
    s = shapes.torus(1500, seed=5)
    write_points_ply(tmp_path / "ring.ply", s.cloud)
    write_curve_ply(tmp_path / "axis.ply", s.curve_vertices, s.curve_edges)
    argv = ["repair", str(tmp_path / "ring.ply"), "--curve", str(tmp_path / "axis.ply"), "--out-curve",
            str(tmp_path / "fixed.swc"), "--log", str(tmp_path / "fixed.json"), "--quiet"]
    err = _refused(argv, capsys)
    assert "cycle" in err and "--lossy" in err and str(tmp_path / "fixed.swc") in err
    assert not (tmp_path / "fixed.swc").exists() and not (tmp_path / "fixed.json").exists()
    assert main([*argv, "--lossy"]) == 0
    assert load_curve(tmp_path / "fixed.swc").n_edges == len(s.curve_edges) - 1  # SWC holds trees only


def test_a_skeletal_set_alone_repairs_and_its_log_replays_on_the_extracted_curve(files, tmp_path, capsys):
    s = shapes.cylinder(1500, seed=4)  # the cloud of `files`; its skeletal set: each point's foot on the axis
    write_points_ply(tmp_path / "sk.ply", s.skeletal)
    base = ["repair", str(files / "cloud.ply"), "--skeletal", str(tmp_path / "sk.ply"), "--out-curve"]
    assert main([*base, str(tmp_path / "c2.ply"), "--log", str(tmp_path / "f.json"), "--out-extracted",
                 str(tmp_path / "c0.ply"), "--quiet"]) == 0
    assert "--out-extracted" not in capsys.readouterr().err
    assert main(["edit", str(tmp_path / "c0.ply"), "--ops", str(tmp_path / "f.json"), "--out",
                 str(tmp_path / "c3.ply")]) == 0
    a, b = load_curve(tmp_path / "c2.ply"), load_curve(tmp_path / "c3.ply")
    assert np.array_equal(a.vertices, b.vertices) and np.array_equal(a.edges, b.edges)
    capsys.readouterr()
    assert main([*base, str(tmp_path / "c4.ply"), "--log", str(tmp_path / "g.json"), "--quiet"]) == 0
    assert "--out-extracted" in capsys.readouterr().err  # a log without its start curve: said how to get it
    err = _refused(["repair", str(files / "cloud.ply"), "--curve", str(files / "axis.ply"), "--out-curve",
                    str(tmp_path / "c5.ply"), "--out-extracted", str(tmp_path / "c6.ply"), "--quiet"], capsys)
    assert "--out-extracted" in err and not (tmp_path / "c5.ply").exists()
