"""Other libraries' objects as inputs: the same skeleton given as an Open3D, trimesh,
networkx, navis, cloud-volume or pandas object scores the same as from its files; the objects are
built with the real libraries (skipped one by one when a library is not installed)."""

from __future__ import annotations

import math
import subprocess
import sys

import numpy as np
import pytest

import skelcore
from skelcore import shapes
from skelcore.errors import SkelInputError
from skelcore.io import load_cloud, load_curve, load_points, write_curve, write_points_ply


@pytest.fixture(scope="module")
def y_files(tmp_path_factory):
    """The Y shape (a tree with a junction): cloud PLY, skeletal PLY, curve SWC with radii, and the
    summaries of the evaluations from those files (with the skeletal set, and of the curve alone)."""
    d = tmp_path_factory.mktemp("y")
    sh = shapes.y_shape(1500, seed=3)
    radius = np.linspace(0.3, 0.1, len(sh.curve_vertices))
    curve = skelcore.CurveSkeleton.from_raw(sh.curve_vertices, sh.curve_edges, radius=radius)
    write_points_ply(d / "cloud.ply", sh.cloud)
    write_points_ply(d / "skeletal.ply", sh.skeletal)
    write_curve(d / "curve.swc", curve)
    cloud, skeletal, curve = load_cloud(d / "cloud.ply"), load_points(d / "skeletal.ply"), load_curve(d / "curve.swc")
    full = skelcore.evaluate(cloud, skeletal=skeletal, curve=curve).summary()
    return sh, curve, {"full": full, "curve": skelcore.evaluate(cloud, curve=curve).summary()}


def _same_summary(a: dict, b: dict) -> None:
    """Equal scores and counts (NaN equal to NaN), timings aside."""
    def flat(d, prefix=""):
        for k, v in d.items():
            if isinstance(v, dict):
                yield from flat(v, f"{prefix}{k}.")
            else:
                yield f"{prefix}{k}", v
    fa, fb = dict(flat(a)), dict(flat(b))
    assert fa.keys() == fb.keys()
    for k in fa:
        x, y = fa[k], fb[k]
        if isinstance(x, float) and isinstance(y, float):
            assert (math.isnan(x) and math.isnan(y)) or x == pytest.approx(y, rel=1e-9, abs=1e-12), k
        else:
            assert x == y, k


def _score(cloud, skeletal, curve) -> dict:
    return skelcore.evaluate(cloud, skeletal=skeletal, curve=curve).summary()


def test_open3d_pointcloud_lineset_and_mesh_score_as_the_files(y_files):
    o3d = pytest.importorskip("open3d")
    sh, curve, ref = y_files
    cloud = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(sh.cloud))
    skeletal = o3d.geometry.PointCloud(o3d.utility.Vector3dVector(sh.skeletal))
    lines = o3d.geometry.LineSet(o3d.utility.Vector3dVector(curve.vertices), o3d.utility.Vector2iVector(curve.edges))
    _same_summary(_score(cloud, skeletal, lines), ref["full"])
    mesh = o3d.geometry.TriangleMesh()
    mesh.vertices = o3d.utility.Vector3dVector(sh.cloud)
    np.testing.assert_array_equal(load_cloud(mesh), sh.cloud)
    np.testing.assert_array_equal(load_curve(lines).edges, curve.edges)


def test_trimesh_pointcloud_mesh_and_path3d_score_as_the_files(y_files):
    trimesh = pytest.importorskip("trimesh")
    sh, curve, ref = y_files
    cloud = trimesh.PointCloud(sh.cloud)
    skeletal = trimesh.Trimesh(vertices=sh.skeletal, faces=np.empty((0, 3), int), process=False)
    from trimesh.path.entities import Line

    path = trimesh.path.Path3D(entities=[Line(e) for e in curve.edges], vertices=curve.vertices, process=False)
    _same_summary(_score(cloud, skeletal, path), ref["full"])


@pytest.mark.parametrize("style", ["pos", "xyz"])
def test_networkx_graph_with_positions_scores_as_the_file(y_files, style):
    nx = pytest.importorskip("networkx")
    sh, curve, ref = y_files
    g = nx.Graph()
    for i, p in enumerate(curve.vertices):
        attrs = {"pos": p} if style == "pos" else dict(zip("xyz", p.tolist()))
        g.add_node(f"node-{i}", radius=curve.radius[i], **attrs)
    g.add_edges_from((f"node-{a}", f"node-{b}") for a, b in curve.edges)
    _same_summary(_score(sh.cloud, None, g), ref["curve"])
    got = load_curve(g)
    np.testing.assert_array_equal(got.vertices, curve.vertices)
    np.testing.assert_array_equal(got.radius, curve.radius)


def _swc_frame(curve):
    import pandas as pd
    from skelcore.io.swc import forest_parents

    parents = forest_parents(curve.n_vertices, curve.edges)
    return pd.DataFrame({"node_id": np.arange(1, curve.n_vertices + 1), "type": 0,
                         "x": curve.vertices[:, 0], "y": curve.vertices[:, 1], "z": curve.vertices[:, 2],
                         "radius": curve.radius, "parent_id": np.where(parents >= 0, parents + 1, -1)})


def test_pandas_swc_rows_and_xyz_frame_score_as_the_files(y_files):
    pd = pytest.importorskip("pandas")
    sh, curve, ref = y_files
    cloud = pd.DataFrame(sh.cloud, columns=["X", "Y", "Z"])
    _same_summary(_score(cloud, None, _swc_frame(curve)), ref["curve"])
    np.testing.assert_array_equal(load_curve(_swc_frame(curve)).radius, curve.radius)


def test_navis_tree_neuron_scores_as_the_file(y_files):
    navis = pytest.importorskip("navis")
    sh, curve, ref = y_files
    neuron = navis.TreeNeuron(_swc_frame(curve))
    _same_summary(_score(sh.cloud, None, neuron), ref["curve"])
    assert load_curve(neuron).radius is not None


def test_cloud_volume_skeleton_scores_as_the_file(y_files):
    try:
        from cloudvolume import Skeleton
    except ImportError:
        Skeleton = pytest.importorskip("osteoid").Skeleton  # kimimaro's Skeleton class
    sh, curve, ref = y_files
    skel = Skeleton(curve.vertices, curve.edges, radii=curve.radius)
    _same_summary(_score(sh.cloud, None, skel), ref["curve"])
    np.testing.assert_array_equal(load_curve(skel).radius, curve.radius)
    # cloud-volume marks unknown radii -1: they are unknown here too
    assert load_curve(Skeleton(curve.vertices, curve.edges)).radius is None


def test_pairs_dicts_and_array_likes_score_as_the_files(y_files):
    sh, curve, ref = y_files
    _same_summary(_score(sh.cloud.tolist(), sh.skeletal.tolist(), (curve.vertices, curve.edges)), ref["full"])
    _same_summary(_score(sh.cloud, None, {"vertices": curve.vertices, "edges": curve.edges}), ref["curve"])


def test_reference_curve_accepts_an_object(y_files):
    nx = pytest.importorskip("networkx")
    sh, curve, _ = y_files
    g = nx.Graph()
    g.add_nodes_from((i, {"pos": p}) for i, p in enumerate(curve.vertices))
    g.add_edges_from(curve.edges.tolist())
    ev = skelcore.evaluate(sh.cloud, curve=curve, reference_curve=g)
    assert ev.reference.f1 == pytest.approx(1.0)


def test_unknown_object_is_one_type_error_naming_what_is_expected():
    with pytest.raises(TypeError, match=r"cloud: cannot use a .*expected an \(N, 3\) array-like, an Open3D") as info:
        skelcore.evaluate(object())
    assert "\n" not in str(info.value)
    with pytest.raises(TypeError, match="as a curve skeleton; expected a CurveSkeleton, a \\(vertices, edges\\)"):
        skelcore.evaluate(np.random.default_rng(0).random((50, 3)), curve=3.5)
    with pytest.raises(TypeError, match="point cloud: cannot use a"):
        load_cloud(object())
    with pytest.raises(TypeError, match=r"cloud: cannot use a str \(a file name: load it with skelcore.load_cloud"):
        skelcore.evaluate("cloud.ply")


def test_objects_without_what_is_needed_are_one_line_input_errors():
    pd = pytest.importorskip("pandas")
    nx = pytest.importorskip("networkx")
    frame = pd.DataFrame({"a": [1.0, 2.0], "b": [3.0, 4.0]})
    with pytest.raises(SkelInputError, match="DataFrame has no SWC columns .*has a, b"):
        load_curve(frame)
    with pytest.raises(SkelInputError, match="no x, y, z columns"):
        load_cloud(frame)
    g = nx.path_graph(3)
    with pytest.raises(SkelInputError, match="networkx node 0 has no position"):
        load_curve(g)
    points = pd.DataFrame(np.random.default_rng(0).random((5, 3)), columns=list("xyz"))
    with pytest.raises(SkelInputError, match="DataFrame has no SWC columns .*has x, y, z"):
        load_curve(points)
    trimesh = pytest.importorskip("trimesh")
    with pytest.raises(SkelInputError, match="trimesh.* has no edges: it is a point set"):
        skelcore.evaluate(points, curve=trimesh.PointCloud(points.to_numpy()))


def test_load_any_sorts_objects_into_curves_and_point_sets():
    nx = pytest.importorskip("networkx")
    g = nx.Graph()
    g.add_node("a", pos=(0, 0, 0))
    g.add_node("b", pos=(1, 0, 0))
    g.add_edge("a", "b")
    assert skelcore.load_any(g).kind == "curve"
    assert skelcore.load_any(np.eye(3)).kind == "points"


def test_importing_skelcore_and_scoring_arrays_imports_none_of_the_libraries():
    code = ("import sys, numpy as np, skelcore\n"
            "from skelcore import shapes\n"
            "sh = shapes.cylinder(600, n_curve=5)\n"
            "skelcore.evaluate(sh.cloud, curve=(sh.curve_vertices, sh.curve_edges))\n"
            "print(sorted(m for m in ('open3d', 'trimesh', 'networkx', 'navis', 'cloudvolume', 'osteoid', 'pandas')"
            " if m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"
