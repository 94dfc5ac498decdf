"""Curve and point-set writers and ``skelcore convert``: every writer's file reads back
the same (vertices, edges, radii), lossy targets are refused with the reason unless --lossy, the
input is never overwritten and an existing output needs --force."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore.cli import main as cli_main
from skelcore.curve import CurveSkeleton
from skelcore.io import load_any, load_curve, load_points, write_curve, write_point_set
from skelcore.io.conversion import convert_file
from skelcore.metrics.reference import graph_counts


def run(*args) -> int:
    return cli_main([str(a) for a in args])


def _tree(radius: bool = True) -> CurveSkeleton:
    """A tree with a junction and random (not round) coordinates and radii."""
    rng = np.random.default_rng(7)
    v = rng.normal(size=(9, 3)) * [3.0, 1.0, 0.1] + 1e3  # large offset: precision is tested too
    e = np.array([[0, 1], [1, 2], [2, 3], [2, 4], [4, 5], [5, 6], [1, 7], [7, 8]])
    return CurveSkeleton.from_raw(v, e, radius=rng.uniform(0.01, 0.5, len(v)) if radius else None)


def _loop() -> CurveSkeleton:
    t = np.linspace(0, 2 * np.pi, 12, endpoint=False)
    v = np.column_stack([np.cos(t), np.sin(t), 0.1 * t])
    e = np.column_stack([np.arange(12), (np.arange(12) + 1) % 12])
    return CurveSkeleton.from_raw(v, e, radius=np.full(12, 0.2))


@pytest.mark.parametrize("suffix", [".ply", ".obj", ".swc", ".cg", ".graphml", ".json"])
def test_every_curve_writer_reads_back_the_same_curve(tmp_path, suffix):
    keeps_radius = suffix not in (".obj", ".cg")
    curve = _tree(radius=keeps_radius)
    write_curve(tmp_path / f"c{suffix}", curve)
    back = load_curve(tmp_path / f"c{suffix}")
    np.testing.assert_array_equal(back.vertices, curve.vertices)
    np.testing.assert_array_equal(back.edges, curve.edges)
    if keeps_radius:
        np.testing.assert_array_equal(back.radius, curve.radius)
    else:
        assert back.radius is None


@pytest.mark.parametrize("suffix", [".ply", ".xyz", ".txt", ".npy", ".obj", ".graphml", ".json"])
def test_every_point_writer_reads_back_the_same_points(tmp_path, suffix):
    pts = np.random.default_rng(1).normal(size=(50, 3)) * 1e-3 + 42.0
    write_point_set(tmp_path / f"p{suffix}", pts)
    loaded = load_any(tmp_path / f"p{suffix}")
    assert loaded.kind == "points"
    np.testing.assert_array_equal(loaded.points, pts)


def test_ascii_ply_and_cycles_survive_where_the_format_holds_them(tmp_path):
    loop = _loop()
    for suffix in (".ply", ".obj", ".cg", ".graphml", ".json"):
        write_curve(tmp_path / f"l{suffix}", loop, binary=False)
        assert graph_counts(load_curve(tmp_path / f"l{suffix}"))["cycles"] == 1


def test_swc_writer_refuses_a_cycle_and_writes_the_spanning_tree_when_lossy(tmp_path):
    with pytest.raises(ValueError, match="1 independent cycle"):
        write_curve(tmp_path / "l.swc", _loop())
    write_curve(tmp_path / "l.swc", _loop(), lossy=True)
    back = load_curve(tmp_path / "l.swc")
    counts = graph_counts(back)
    assert (back.n_vertices, back.n_edges, counts["components"], counts["cycles"]) == (12, 11, 1, 0)


def test_swc_from_skelscope_reads_in_navis_and_networkx_reads_the_graphml(tmp_path):
    navis = pytest.importorskip("navis")
    nx = pytest.importorskip("networkx")
    curve = _tree()
    write_curve(tmp_path / "t.swc", curve)
    write_curve(tmp_path / "t.graphml", curve)
    neuron = navis.read_swc(str(tmp_path / "t.swc"))
    assert neuron.n_nodes == curve.n_vertices and len(neuron.edges) == curve.n_edges
    np.testing.assert_allclose(np.sort(neuron.nodes["radius"].to_numpy()), np.sort(curve.radius))
    g = nx.read_graphml(tmp_path / "t.graphml")
    assert g.number_of_nodes() == curve.n_vertices and g.number_of_edges() == curve.n_edges
    assert g.nodes["n4"]["x"] == curve.vertices[4, 0] and g.nodes["n4"]["radius"] == curve.radius[4]


# ---- skelcore convert ----------------------------------------------------------------------------


@pytest.mark.parametrize("target", ["t.swc", "t.graphml", "t.json", "t.ply"])
def test_convert_prints_the_comparison_and_exits_0(tmp_path, capsys, target):
    write_curve(tmp_path / "in.ply", _tree())
    assert run("convert", tmp_path / "in.ply", tmp_path / target) == 0
    out = capsys.readouterr().out
    assert "curve, 9 vertices, 8 edges, 1 component, 0 cycles, radii" in out
    assert out.count("9 vertices, 8 edges") == 2
    assert "largest coordinate change 0, radius change 0" in out and "read back: the same" in out


def test_convert_a_point_set(tmp_path, capsys):
    pts = np.random.default_rng(2).random((30, 3))
    np.save(tmp_path / "p.npy", pts)
    assert run("convert", tmp_path / "p.npy", tmp_path / "p.ply") == 0
    assert "point set, 30 points" in capsys.readouterr().out
    np.testing.assert_array_equal(load_points(tmp_path / "p.ply"), pts)
    assert run("convert", tmp_path / "p.npy", tmp_path / "p.swc", "--lossy") == 2
    assert capsys.readouterr().err.strip() == (
        f"skelcore: error: {tmp_path / 'p.swc'}: .swc holds curve skeletons only (a point set has no edges)")


@pytest.mark.parametrize("curve, target, reason", [
    (_loop, "o.swc", "SWC holds trees only: the curve has 1 independent cycle(s)"),
    (_tree, "o.obj", "OBJ has no vertex radius: the curve's radii would be lost"),
    (_tree, "o.cg", ".cg has no vertex radius"),
    (_tree, "o.xyz", ".xyz holds points only: the curve's 8 edges would be lost"),
])
def test_a_lossy_target_is_refused_in_one_line_unless_lossy(tmp_path, capsys, curve, target, reason):
    write_curve(tmp_path / "in.json", curve())
    assert run("convert", tmp_path / "in.json", tmp_path / target) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and reason in err[0] and "--lossy" in err[0]
    assert not (tmp_path / target).exists()
    assert run("convert", tmp_path / "in.json", tmp_path / target, "--lossy") == 0
    assert "lossy (--lossy): " + reason.split(":")[0] in capsys.readouterr().out


def test_convert_never_overwrites_its_input_and_needs_force_for_an_existing_output(tmp_path, capsys):
    write_curve(tmp_path / "in.swc", _tree())
    before = (tmp_path / "in.swc").read_bytes()
    assert run("convert", tmp_path / "in.swc", tmp_path / "in.swc", "--force") == 2
    assert "never overwrites its input" in capsys.readouterr().err
    assert (tmp_path / "in.swc").read_bytes() == before
    (tmp_path / "out.ply").write_text("precious")
    assert run("convert", tmp_path / "in.swc", tmp_path / "out.ply") == 2
    assert "exists: give --force" in capsys.readouterr().err
    assert (tmp_path / "out.ply").read_text() == "precious"
    assert run("convert", tmp_path / "in.swc", tmp_path / "out.ply", "--force") == 0
    assert load_curve(tmp_path / "out.ply").n_edges == 8


def test_convert_bad_inputs_are_one_line_exit_2(tmp_path, capsys):
    (tmp_path / "g.graphml").write_text(
        '<?xml version="1.0"?><graphml xmlns="http://graphml.graphdrawing.org/xmlns"><graph edgedefault="undirected">'
        '<node id="a"/><node id="b"/><edge source="a" target="b"/></graph></graphml>')
    assert run("convert", tmp_path / "g.graphml", tmp_path / "g.ply") == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "GraphML node 'a' has no 3-D position" in err[0]
    write_curve(tmp_path / "in.ply", _tree())
    assert run("convert", tmp_path / "in.ply", tmp_path / "out.vtk") == 2
    assert "cannot write .vtk files" in capsys.readouterr().err
    assert run("convert", tmp_path / "missing.ply", tmp_path / "o.ply") == 2
    assert "file not found" in capsys.readouterr().err


def test_convert_file_as_points_reads_a_curve_file_as_its_vertices(tmp_path):
    write_curve(tmp_path / "in.ply", _tree())
    result = convert_file(tmp_path / "in.ply", tmp_path / "v.npy", as_kind="points")
    assert result.source.kind == "points" and result.same


def test_convert_file_can_replace_its_own_earlier_output(tmp_path):
    write_curve(tmp_path / "in.ply", _tree())
    first = convert_file(tmp_path / "in.ply", tmp_path / "out.json")
    again = convert_file(tmp_path / "in.ply", tmp_path / "out.json", force=True)
    assert first.same and again.same
