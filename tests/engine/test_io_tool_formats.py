"""Other tools' skeleton files: networkx's GraphML and GEXF (parsed with entity expansion
refused), TreeQSM ``.mat`` cylinder models, AdTree's PLY graph, Point2Skeleton's outputs, and a radius
per vertex from PLY and SWC kept on the curve."""

from __future__ import annotations

import numpy as np
import pytest
from plyfile import PlyData, PlyElement

import skelcore
from skelcore import shapes
from skelcore.errors import SkelInputError
from skelcore.io import load_any, load_cloud, load_curve, load_points
from skelcore.metrics.reference import graph_counts


@pytest.fixture
def y_curve():
    sh = shapes.y_shape(600, n_curve_per_arm=5, seed=1)
    return sh.curve_vertices, sh.curve_edges


# ---- GraphML / GEXF ------------------------------------------------------------------------------


def _graph(vertices, edges, nx, style):
    g = nx.Graph()
    for i, p in enumerate(vertices):
        if style == "xyz":
            g.add_node(f"v{i}", x=float(p[0]), y=float(p[1]), z=float(p[2]), radius=0.1 + i)
        else:
            g.add_node(f"v{i}", viz={"position": dict(zip("xyz", map(float, p)))})
    g.add_edges_from((f"v{a}", f"v{b}") for a, b in edges)
    return g


@pytest.mark.parametrize("writer, style", [("graphml", "xyz"), ("gexf", "xyz"), ("gexf", "viz")])
def test_networkx_graphml_and_gexf_load_as_the_curve(tmp_path, y_curve, writer, style):
    nx = pytest.importorskip("networkx")
    v, e = y_curve
    path = tmp_path / f"g.{writer}"
    getattr(nx, f"write_{writer}")(_graph(v, e, nx, style), path)
    curve = load_curve(path)
    np.testing.assert_array_equal(curve.vertices, v)
    np.testing.assert_array_equal(curve.edges, np.sort(e, axis=1)[np.lexsort(np.sort(e, axis=1).T[::-1])])
    if style == "xyz":
        np.testing.assert_array_equal(curve.radius, 0.1 + np.arange(len(v)))
    assert load_any(path).kind == "curve"


def test_graphml_read_by_content_whatever_its_name(tmp_path, y_curve):
    nx = pytest.importorskip("networkx")
    nx.write_graphml(_graph(*y_curve, nx, "xyz"), tmp_path / "graph.xml")
    assert load_curve(tmp_path / "graph.xml").n_vertices == len(y_curve[0])


def test_graphml_without_positions_is_one_line(tmp_path):
    nx = pytest.importorskip("networkx")
    nx.write_graphml(nx.path_graph(4), tmp_path / "p.graphml")
    with pytest.raises(SkelInputError, match=r"p.graphml: GraphML node '0' has no 3-D position .*attributes: none"):
        load_curve(tmp_path / "p.graphml")


@pytest.mark.parametrize("entity", [
    '<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;"><!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;">',
    '<!ENTITY x SYSTEM "file:///etc/passwd">',
])
def test_xml_entities_are_refused_not_expanded(tmp_path, entity):
    (tmp_path / "bad.graphml").write_text(
        f'<?xml version="1.0"?><!DOCTYPE graphml [{entity}]>'
        '<graphml xmlns="http://graphml.graphdrawing.org/xmlns"><key id="d0" for="node" attr.name="x"/>'
        '<graph><node id="n"><data key="d0">&c;</data></node></graph></graphml>'.replace("&c;", "&c;" if "ENTITY c" in entity else "&x;"))
    with pytest.raises(SkelInputError, match="XML declares entities; not read"):
        load_curve(tmp_path / "bad.graphml")


def test_malformed_xml_is_one_line(tmp_path):
    (tmp_path / "m.graphml").write_text("<graphml><graph><node id='a'></graph>")
    with pytest.raises(SkelInputError, match=r"m.graphml: malformed XML: mismatched tag at line 1"):
        load_curve(tmp_path / "m.graphml")


# ---- TreeQSM ---------------------------------------------------------------------------------------


def _qsm_cylinders():
    """A trunk of three unit cylinders up z and a two-cylinder branch leaving the middle cylinder's
    side at height 1.5 along x (start on its surface, radius 0.25 away from the axis)."""
    start = np.array([[0, 0, 0], [0, 0, 1], [0, 0, 2], [0.25, 0, 1.5], [1.25, 0, 1.5]], float)
    axis = np.array([[0, 0, 1], [0, 0, 1], [0, 0, 1], [1, 0, 0], [1, 0, 0]], float)
    length = np.ones(5)
    radius = np.array([0.3, 0.25, 0.2, 0.1, 0.08])
    parent = np.array([0, 1, 2, 2, 4])  # 1-based, 0 = none (TreeQSM)
    return start, axis, length, radius, parent


def test_treeqsm_mat_loads_as_a_tree_with_radii(tmp_path):
    from scipy.io import savemat

    start, axis, length, radius, parent = _qsm_cylinders()
    savemat(tmp_path / "QSM.mat", {"QSM": {"cylinder": {"start": start, "axis": axis, "length": length,
                                                         "radius": radius, "parent": parent,
                                                         "extension": np.array([2, 3, 0, 5, 0])}}})
    curve = load_curve(tmp_path / "QSM.mat")
    counts = graph_counts(curve)
    # 4 trunk points + the split at height 1.5 + the branch's 3 points; 3 + 1 (split) + 1 (join) + 2 edges
    assert (curve.n_vertices, curve.n_edges, counts["components"], counts["cycles"]) == (8, 7, 1, 0)
    by_position = {tuple(np.round(p, 9)): r for p, r in zip(curve.vertices, curve.radius)}
    assert by_position[(0.0, 0.0, 3.0)] == 0.2 and by_position[(0.0, 0.0, 1.5)] == 0.25
    assert by_position[(0.25, 0.0, 1.5)] == 0.1 and by_position[(2.25, 0.0, 1.5)] == 0.08
    assert counts["junctions"] == 1 and counts["endpoints"] == 3


def test_treeqsm_2_variables_without_parents_join_by_position(tmp_path):
    from scipy.io import savemat

    start, axis, length, radius, _ = _qsm_cylinders()
    savemat(tmp_path / "old.mat", {"Sta": start[:3], "Axe": axis[:3], "Len": length[:3], "Rad": radius[:3]})
    curve = load_curve(tmp_path / "old.mat")
    assert (curve.n_vertices, curve.n_edges) == (4, 3)
    np.testing.assert_array_equal(np.sort(curve.vertices[:, 2]), [0, 1, 2, 3])


def test_treeqsm_trunk_scores_a_cylinder_cloud_bounded(tmp_path):
    from scipy.io import savemat

    sh = shapes.cylinder(1500, radius=0.5, length=3.0, seed=2)
    z0, z1 = sh.curve_vertices[:, 2].min(), sh.curve_vertices[:, 2].max()
    n = 6
    starts = np.column_stack([np.zeros(n), np.zeros(n), np.linspace(z0, z1, n + 1)[:-1]])
    savemat(tmp_path / "t.mat", {"qsm": {"cylinder": {
        "start": starts, "axis": np.tile([0.0, 0, 1], (n, 1)), "length": np.full(n, (z1 - z0) / n),
        "radius": np.full(n, 0.5), "parent": np.arange(n)}}})
    ev = skelcore.evaluate(sh.cloud, curve=load_curve(tmp_path / "t.mat"))
    assert ev.summary()["boundedness"]["curve"] == 1.0


def test_mat_without_a_cylinder_model_is_one_line(tmp_path, capsys):
    from scipy.io import savemat

    savemat(tmp_path / "x.mat", {"points": np.eye(3), "name": "tree"})
    with pytest.raises(SkelInputError, match=r"x.mat: .mat file holds no TreeQSM cylinder model .*variables: points, name"):
        load_curve(tmp_path / "x.mat")
    from skelcore.cli import main

    assert main(["convert", str(tmp_path / "x.mat"), str(tmp_path / "x.ply")]) == 2
    assert len(capsys.readouterr().err.strip().splitlines()) == 1


# ---- AdTree, Point2Skeleton, radius per vertex -----------------------------------------------------


def test_adtree_skeleton_ply_with_list_edges_and_radius(tmp_path, y_curve):
    # AdTree saves its skeleton with easy3d's graph PLY: float x y z (+ radius), edges as a list
    # property vertex_indices of two indices
    v, e = y_curve
    r = np.linspace(0.5, 0.1, len(v)).astype("f4")
    vertex = np.array([tuple(p) + (q,) for p, q in zip(v.astype("f4"), r)],
                      dtype=[("x", "f4"), ("y", "f4"), ("z", "f4"), ("radius", "f4")])
    edge = np.empty(len(e), dtype=[("vertex_indices", "O")])
    edge["vertex_indices"] = [np.array(row, dtype="i4") for row in e]
    PlyData([PlyElement.describe(vertex, "vertex"),
             PlyElement.describe(edge, "edge", val_types={"vertex_indices": "i4"}, len_types={"vertex_indices": "u1"})],
            text=False).write(str(tmp_path / "tree_skeleton.ply"))
    curve = load_curve(tmp_path / "tree_skeleton.ply")
    assert curve.n_edges == len(e)
    np.testing.assert_array_equal(curve.vertices, v.astype("f4").astype(float))
    np.testing.assert_array_equal(curve.radius, r.astype(float))


def test_point2skeleton_outputs(tmp_path, y_curve):
    # Point2Skeleton (test.py / FileRW.py) writes per shape: _center.off (skeletal points, no faces),
    # _edge.obj (v lines, then 'l i j' with 1-based indices), _graph_*.obj ('g line' groups) and, when
    # asked, an .xyzr list (a count line, then x y z r)
    v, e = y_curve
    vs = "".join(f"v {x} {y} {z}\n" for x, y, z in v)
    (tmp_path / "0_center.off").write_text(f"OFF\n{len(v)} 0 0\n" + "".join(f"{x} {y} {z}\n" for x, y, z in v))
    (tmp_path / "0_edge.obj").write_text(vs + "".join(f"l {a + 1} {b + 1}\n" for a, b in e))
    (tmp_path / "0_graph_pred.obj").write_text("g line\n" + vs + "g\n" + "".join(f"l {a + 1} {b + 1}\n" for a, b in e))
    (tmp_path / "0_skel.xyzr").write_text(f"{len(v)}\n" + "".join(f"{x} {y} {z} 0.1\n" for x, y, z in v))
    (tmp_path / "0_face.obj").write_text(vs + "f 1 2 3\n")
    np.testing.assert_array_equal(load_points(tmp_path / "0_center.off"), v)
    for name in ("0_edge.obj", "0_graph_pred.obj"):
        curve = load_curve(tmp_path / name)
        np.testing.assert_array_equal(curve.vertices, v)
        assert curve.n_edges == len(e)
    np.testing.assert_array_equal(load_points(tmp_path / "0_skel.xyzr"), v)
    with pytest.raises(SkelInputError, match="no edges: it is a point set"):
        load_curve(tmp_path / "0_face.obj")


def test_swc_radius_is_kept_and_nonpositive_is_unknown(tmp_path):
    rows = ["1 1 0 0 0 0.5 -1", "2 3 0 0 1 0.4 1", "3 3 0 1 1 -1 2"]
    (tmp_path / "n.swc").write_text("\n".join(rows) + "\n")
    r = load_curve(tmp_path / "n.swc").radius
    assert r[0] == 0.5 and r[1] == 0.4 and np.isnan(r[2])
    (tmp_path / "z.swc").write_text("\n".join(row.rsplit(" ", 2)[0] + " 0 " + row.rsplit(" ", 1)[1] for row in rows))
    assert load_curve(tmp_path / "z.swc").radius is None


def test_ply_radius_property_is_kept_through_both_readers(tmp_path, y_curve):
    from skelcore.io import write_curve_ply

    v, e = y_curve
    r = np.linspace(1, 2, len(v))
    write_curve_ply(tmp_path / "b.ply", v, e, scalars={"radius": r})
    write_curve_ply(tmp_path / "a.ply", v, e, scalars={"radius": r}, binary=False)
    for name in ("a.ply", "b.ply"):
        np.testing.assert_array_equal(load_curve(tmp_path / name).radius, r)
    assert load_cloud(tmp_path / "b.ply").shape == (len(v), 3)
