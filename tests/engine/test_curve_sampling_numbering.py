"""Vertex numbering and curve sampling (docs/metrics.md 3): the toolbox's sampling walks every edge
from its lower-index vertex, so renumbering a curve moves its samples; ``curve_sampling="invariant"``
walks every branch from a canonical end and scores every numbering alike. Objects of other libraries
that keep a file's vertex order score as the file under the default."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import skelcore
from skelcore import shapes
from skelcore.cli import main
from skelcore.curve import CurveSkeleton
from skelcore.io import load_curve, write_curve, write_points_ply
from skelcore.metrics.curve_sampling import canonical_edges, sample_curve
from skelcore.params import Params

INVARIANT = Params(curve_sampling="invariant")


def _relabel(v: np.ndarray, e: np.ndarray, seed: int) -> tuple[np.ndarray, np.ndarray]:
    """The same graph: vertices permuted, edges reordered and some reversed."""
    rng = np.random.default_rng(seed)
    perm = rng.permutation(len(v))
    e2 = np.argsort(perm)[np.asarray(e)]
    e2 = e2[rng.permutation(len(e2))]
    flip = rng.random(len(e2)) < 0.5
    e2[flip] = e2[flip][:, ::-1]
    return v[perm], e2


def _graphs() -> dict[str, tuple[np.ndarray, np.ndarray]]:
    rng = np.random.default_rng(4)
    sh = shapes.y_shape(600, seed=1)
    loop = np.column_stack([np.cos(np.arange(9) * 0.7), np.sin(np.arange(9) * 0.7), rng.normal(size=9) * 0.1])
    ring = np.column_stack([np.arange(9), (np.arange(9) + 1) % 9])
    # a junction carrying a lasso (a loop back to itself) and two arms
    lasso_v = rng.normal(size=(7, 3))
    lasso_e = np.array([[0, 1], [1, 2], [2, 3], [3, 0], [0, 4], [4, 5], [0, 6]])
    two = shapes.torus(200).curve_vertices
    return {
        "y": (sh.curve_vertices, sh.curve_edges),
        "loop": (loop, ring),
        "lasso": (lasso_v, lasso_e),
        "loop and path": (np.vstack([loop, two[:5] + 3]), np.vstack([ring, [[9, 10], [10, 11], [11, 12], [12, 13]]])),
    }


@pytest.mark.parametrize("name", sorted(_graphs()))
@pytest.mark.parametrize("seed", [0, 1, 2])
def test_invariant_samples_do_not_depend_on_the_numbering(name, seed):
    v, e = _graphs()[name]
    a = sample_curve(CurveSkeleton.from_raw(v, e), 60, method="invariant")
    b = sample_curve(CurveSkeleton.from_raw(*_relabel(v, e, seed)), 60, method="invariant")
    np.testing.assert_array_equal(a.points, b.points)  # the same samples in the same order
    np.testing.assert_allclose(np.abs(np.einsum("ij,ij->i", np.nan_to_num(a.directions), np.nan_to_num(b.directions))),
                               np.isfinite(a.directions[:, 0]).astype(float), atol=1e-12)
    np.testing.assert_array_equal(np.isnan(a.directions[:, 0]), np.isnan(b.directions[:, 0]))


@pytest.mark.parametrize("name", sorted(_graphs()))
def test_invariant_sampling_keeps_the_counts_and_the_edge_fractions(name):
    """Same samples per edge as the toolbox; t still measured from the edge's lower-index vertex."""
    curve = CurveSkeleton.from_raw(*_graphs()[name])
    tool, inv = sample_curve(curve, 60), sample_curve(curve, 60, method="invariant")
    np.testing.assert_array_equal(np.bincount(tool.edge, minlength=curve.n_edges),
                                  np.bincount(inv.edge, minlength=curve.n_edges))
    lo, hi = curve.vertices[curve.edges[inv.edge, 0]], curve.vertices[curve.edges[inv.edge, 1]]
    np.testing.assert_allclose(lo + inv.t[:, None] * (hi - lo), inv.points, atol=1e-12)
    assert np.all((inv.t >= 0) & (inv.t <= 1))


def test_every_inner_vertex_of_a_branch_is_sampled_once_and_the_smaller_end_never():
    v = np.array([[3.0, 0, 0], [0, 0, 0], [1, 0, 0], [2, 0, 0]])  # the path x = 0, 1, 2, 3, numbered oddly
    e = np.array([[0, 3], [3, 2], [2, 1]])
    # toolbox: edges (0, 3), (2, 3), (1, 2) walked from their lower index: x = 2 twice, x = 3 never
    assert sorted(sample_curve(CurveSkeleton.from_raw(v, e), 3).points[:, 0].tolist()) == [1.0, 2.0, 2.0]
    for seed in range(4):
        inv = sample_curve(CurveSkeleton.from_raw(*_relabel(v, e, seed)), 3, method="invariant")
        assert inv.points[:, 0].tolist() == [1.0, 2.0, 3.0]


def test_canonical_edges_cover_every_edge_once():
    v, e = _graphs()["lasso"]
    rows, oriented = canonical_edges(v, e)
    assert sorted(rows.tolist()) == list(range(len(e)))
    np.testing.assert_array_equal(np.sort(oriented, axis=1), np.sort(e[rows], axis=1))


# ---- overall scores ----------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def jittered_y():
    """A Y whose curve is off the axis (so the samples' places matter) and three renumberings of it."""
    sh = shapes.y_shape(1500, seed=3)
    jitter = np.random.default_rng(0).normal(scale=0.06, size=sh.curve_vertices.shape)
    jitter[:, 2] = 0
    v = sh.curve_vertices + jitter
    return sh.cloud, (v, sh.curve_edges), [_relabel(v, sh.curve_edges, s) for s in range(3)]


def _flat(summary: dict, prefix: str = "") -> dict:
    out = {}
    for k, x in summary.items():
        if k == "coverage":
            continue
        out.update(_flat(x, f"{prefix}{k}.") if isinstance(x, dict) else {f"{prefix}{k}": x})
    return out


def _curve_scores(cloud, curve, params=Params()) -> dict:
    return _flat(skelcore.evaluate(cloud, curve=curve, params=params).summary())


def test_renumbering_changes_nothing_under_invariant_sampling(jittered_y):
    cloud, curve, relabelled = jittered_y
    ref = _curve_scores(cloud, curve, INVARIANT)
    for other in relabelled:
        got = _curve_scores(cloud, other, INVARIANT)
        assert got.keys() == ref.keys()
        for k, x in ref.items():
            y = got[k]
            assert (x is None and y is None) or (isinstance(x, float) and math.isnan(x) and math.isnan(y)) \
                or y == pytest.approx(x, abs=1e-12), k


def test_renumbering_moves_the_toolbox_samples(jittered_y):
    """Under the default each edge is walked from its lower-index vertex: a path's lowest-index end is
    never sampled and an inner vertex is sampled 0, 1 or 2 times, so another numbering of the same Y
    scores another curve centeredness (and sample count)."""
    cloud, curve, relabelled = jittered_y
    ref = _curve_scores(cloud, curve)
    scores = [_curve_scores(cloud, other) for other in relabelled]
    assert any(s["centeredness.curve"] != ref["centeredness.curve"] for s in scores)
    assert any(s["counts.centeredness.curve"] != ref["counts.centeredness.curve"] for s in scores)


def test_params_and_cli_take_the_sampling_and_refuse_other_values(tmp_path, capsys):
    with pytest.raises(ValueError, match="curve_sampling"):
        Params(curve_sampling="sorted")
    sh = shapes.y_shape(600, seed=2)
    write_points_ply(tmp_path / "cloud.ply", sh.cloud)
    write_curve(tmp_path / "curve.ply", CurveSkeleton.from_raw(sh.curve_vertices, sh.curve_edges))
    args = ["evaluate", str(tmp_path / "cloud.ply"), "--curve", str(tmp_path / "curve.ply"), "--quiet"]
    assert main(args + ["--curve-sampling", "invariant", "--json", str(tmp_path / "r.json")]) == 0
    assert "curve sampling: invariant" in capsys.readouterr().out
    assert '"curve_sampling": "invariant"' in (tmp_path / "r.json").read_text()
    assert main(args + ["--curve-sampling", "sorted"]) == 2
    err = capsys.readouterr().err.strip()
    assert err == "skelcore: error: --curve-sampling must be toolbox or invariant, got 'sorted'"


# ---- other libraries' objects read from a file -----------------------------------------------------

@pytest.fixture(scope="module")
def y_file(tmp_path_factory, jittered_y):
    """The jittered Y renumbered, as SWC and GraphML files, and its scores from the files."""
    cloud, _, relabelled = jittered_y
    d = tmp_path_factory.mktemp("numbering")
    curve = CurveSkeleton.from_raw(*relabelled[0])
    write_curve(d / "y.swc", curve)
    write_curve(d / "y.graphml", curve)
    ref = {"toolbox": _curve_scores(cloud, load_curve(d / "y.swc")),
           "invariant": _curve_scores(cloud, load_curve(d / "y.swc"), INVARIANT)}
    assert _curve_scores(cloud, load_curve(d / "y.graphml")) == ref["toolbox"]
    return cloud, d, ref


def test_networkx_pandas_and_trimesh_objects_from_the_file_keep_its_order(y_file):
    nx, pd, trimesh = (pytest.importorskip(m) for m in ("networkx", "pandas", "trimesh"))
    from trimesh.path.entities import Line

    cloud, d, ref = y_file
    graph = nx.read_graphml(d / "y.graphml")
    table = pd.read_csv(d / "y.swc", sep=r"\s+", comment="#", header=None,
                        names=["node_id", "type", "x", "y", "z", "radius", "parent_id"])
    c = load_curve(d / "y.swc")
    path = trimesh.path.Path3D(entities=[Line(e) for e in c.edges], vertices=c.vertices, process=False)
    for obj in (graph, table, path):
        assert _curve_scores(cloud, obj) == ref["toolbox"], type(obj).__name__


def test_objects_that_renumber_score_as_the_file_only_under_invariant_sampling(y_file):
    """trimesh.load_path merges the segments' end points in its own order (not the file's): its
    numbering differs, so its toolbox scores may differ from the file's; the invariant ones do not."""
    trimesh = pytest.importorskip("trimesh")
    cloud, d, ref = y_file
    c = load_curve(d / "y.swc")
    path = trimesh.load_path(c.vertices[c.edges])
    assert not np.array_equal(np.asarray(path.vertices), c.vertices)
    assert _curve_scores(cloud, path, INVARIANT) == pytest.approx(ref["invariant"], abs=1e-12)


def test_navis_keeps_the_order_but_stores_float32(y_file):
    """navis.read_swc keeps the file's rows in order but holds x, y, z as float32: the same samples
    up to float32 rounding, so the scores agree to about 1e-6 (smoothness) rather than exactly."""
    navis = pytest.importorskip("navis")
    cloud, d, ref = y_file
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        neuron = navis.read_swc(str(d / "y.swc"))
    got = _curve_scores(cloud, neuron)
    assert got["counts.centeredness.curve"] == ref["toolbox"]["counts.centeredness.curve"]
    assert got["smoothness.curve"] == pytest.approx(ref["toolbox"]["smoothness.curve"], abs=1e-5)
