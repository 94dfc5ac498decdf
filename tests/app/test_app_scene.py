"""The viewer's Qt-free parts: the scene model, file roles, the summary table's text."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest

from skelscope.loading import REPLACE_CLOUD, assign_roles, is_complete_set
from skelscope.panels.summary import summary_cells
from skelscope.scene import Scene, format_element_info
from skelcore.curve import CurveSkeleton


def _loaded(kind: str, n: int, name: str, spread: float = 1.0) -> SimpleNamespace:
    if kind == "curve":
        return SimpleNamespace(kind="curve", path=f"/d/{name}", points=None, curve=object())
    pts = np.random.default_rng(n).normal(size=(n, 3))
    pts[:, 1:] *= spread  # squeezed towards the x axis, as a contraction does
    return SimpleNamespace(kind="points", path=f"/d/{name}", points=pts, curve=None)


def test_edges_make_a_curve_the_wider_same_size_set_is_the_cloud_the_other_skeletal():
    items = [
        _loaded("points", 100, "s.ply", spread=0.01), _loaded("curve", 0, "c.ply"), _loaded("points", 100, "cloud.ply")
    ]
    roles = assign_roles(items, None, lambda q, o: pytest.fail("asked"))
    assert [(a.role, a.loaded.path) for a in roles] == [
        ("cloud", "/d/cloud.ply"), ("skeletal", "/d/s.ply"), ("curve", "/d/c.ply")
    ]


def test_same_size_same_spread_point_sets_without_cloud_ask_which_is_the_cloud():
    items = [_loaded("points", 50, "a.ply"), _loaded("points", 50, "b.ply")]
    roles = assign_roles(items, None, lambda q, options: "b.ply")
    assert {a.role: a.loaded.path for a in roles} == {"cloud": "/d/b.ply", "skeletal": "/d/a.ply"}


def test_point_set_of_another_size_than_the_loaded_cloud_asks_and_can_be_skipped():
    items = [_loaded("points", 70, "other.ply")]
    questions = []

    def ask(q, options):
        questions.append((q, options))
        return None

    assert assign_roles(items, 100, ask) == []
    assert "70 points but the cloud has 100" in questions[0][0]
    # The default answer (Enter) skips the file: an ambiguous drop never replaces the loaded cloud.
    assert assign_roles(items, 100, lambda q, options: options[0]) == []
    roles = assign_roles(items, 100, lambda q, options: REPLACE_CLOUD)
    assert [a.role for a in roles] == ["cloud"]


def test_a_complete_set_dropped_on_a_loaded_window_is_assigned_within_itself():
    # cloud 100 loaded; a new set of another size (cloud, skeletal, curve): no question, right roles
    items = [_loaded("points", 60, "new_skeletal.ply", spread=0.01), _loaded("points", 60, "new_cloud.ply"),
             _loaded("curve", 0, "new_curve.ply")]
    roles = assign_roles(items, 100, lambda q, o: pytest.fail(f"asked {q}"))
    assert [(a.role, a.loaded.path) for a in roles] == [
        ("cloud", "/d/new_cloud.ply"), ("skeletal", "/d/new_skeletal.ply"), ("curve", "/d/new_curve.ply")]
    # the same set with the loaded cloud's size: still within itself (not "skeletal + ask")
    items = [_loaded("points", 100, "s.ply", spread=0.01), _loaded("points", 100, "c.ply")]
    roles = assign_roles(items, 100, lambda q, o: pytest.fail(f"asked {q}"))
    assert {a.role: a.loaded.path for a in roles} == {"cloud": "/d/c.ply", "skeletal": "/d/s.ply"}
    # a cloud dropped with its curve skeleton
    items = [_loaded("curve", 0, "k.ply"), _loaded("points", 70, "other.ply")]
    assert is_complete_set(items, 100)
    roles = assign_roles(items, 100, lambda q, o: pytest.fail(f"asked {q}"))
    assert [(a.role, a.loaded.path) for a in roles] == [("cloud", "/d/other.ply"), ("curve", "/d/k.ply")]


def test_scene_closes_layers_and_swaps_cloud_and_skeletal():
    scene = Scene()
    rng = np.random.default_rng(1)
    a, b = rng.normal(size=(30, 3)), rng.normal(size=(30, 3)) * 0.1
    scene.set_cloud(a, "/d/a.ply")
    scene.set_skeletal(b, "/d/b.ply")
    scene.set_point_size("cloud", 3.0)
    scene.swap_cloud_and_skeletal()
    assert scene.cloud.path == "/d/b.ply" and np.array_equal(scene.cloud.points, b)
    assert scene.skeletal.path == "/d/a.ply" and np.array_equal(scene.skeletal.points, a)
    assert scene.cloud.point_size == 2.0  # a new cloud's display, not the old skeletal set's
    scene.remove_layer("skeletal")
    assert set(scene.layers) == {"cloud"}
    scene.swap_cloud_and_skeletal()  # only a cloud: it becomes the skeletal set
    assert set(scene.layers) == {"skeletal"}
    scene.set_curve(_y_curve())
    scene.clear()
    assert scene.layers == {}


def test_style_options_are_checked_and_emit_one_event():
    scene = Scene()
    events = []
    scene.subscribe(lambda e: events.append((e.kind, e.layer)))
    scene.set_style("spheres", True)
    scene.set_style("spheres", True)
    assert events == [("style", "spheres")] and scene.style["spheres"]
    with pytest.raises(ValueError):
        scene.set_style("glow", True)


def test_tube_polylines_run_through_the_samples_in_order():
    from skelscope.view.actors import curve_polylines

    v = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0]], float)
    edges = np.array([[0, 1], [1, 2]])
    samples = np.array([[0.75, 0, 0], [0.25, 0, 0], [1, 0.5, 0]])
    pts, cells, vals = curve_polylines(v, edges, np.array([0.3, 0.1, 0.9]), "samples", samples,
                                       np.array([0, 0, 1]), np.array([0.75, 0.25, 0.5]))
    # edge 0: v0, sample t=0.25, sample t=0.75, v1; edge 1: v1, sample, v2
    assert cells.tolist() == [4, 0, 1, 2, 3, 3, 4, 5, 6]
    assert np.allclose(pts[:4, 0], [0, 0.25, 0.75, 1]) and np.allclose(vals[1:3], [0.1, 0.3])
    assert vals[0] == 0.1 and vals[3] == 0.3  # a vertex takes its nearest sample's value
    pts, cells, vals = curve_polylines(v, edges, np.array([0.5, np.nan, 1.0]), "vertices")
    assert cells.tolist() == [2, 0, 1, 2, 1, 2] and np.isnan(vals[1])


def test_point_set_with_the_loaded_clouds_count_becomes_skeletal_without_asking():
    roles = assign_roles([_loaded("points", 100, "s.ply")], 100, lambda q, o: pytest.fail("asked"))
    assert [a.role for a in roles] == ["skeletal"]


def _y_curve() -> CurveSkeleton:
    v = np.array([[0, 0, 0], [1, 0, 0], [2, 0, 0], [0, 1, 0], [0, -1, 0]], float)
    return CurveSkeleton.from_raw(v, np.array([[0, 1], [1, 2], [0, 3], [0, 4]]))


def test_scene_quantity_length_must_match_and_range_ignores_nan():
    scene = Scene()
    layer = scene.set_skeletal(np.random.default_rng(0).normal(size=(10, 3)))
    with pytest.raises(ValueError, match="has 9 values"):
        layer.add_scalar_quantity("boundedness", np.zeros(9))
    q = layer.add_scalar_quantity("boundedness", np.r_[np.nan, np.linspace(0.2, 0.8, 9)])
    assert q.n_invalid == 1
    assert q.finite_range() == pytest.approx((0.2, 0.8))
    assert scene.data_range() == pytest.approx((0.2, 0.8))
    assert scene.n_invalid_shown() == 1
    scene.set_visible("skeletal", False)
    assert scene.n_invalid_shown() == 0


def test_loading_new_inputs_drops_the_evaluation_and_emits_events():
    scene = Scene()
    events = []
    scene.subscribe(lambda e: events.append((e.kind, e.layer)))
    scene.set_cloud(np.random.default_rng(0).normal(size=(20, 3)))
    scene.evaluation = object()
    scene.set_curve(_y_curve())
    assert scene.evaluation is None
    assert ("layer", "cloud") in events and ("layer", "curve") in events
    with pytest.raises(ValueError):
        scene.set_metric("roundness")
    with pytest.raises(ValueError):
        scene.set_clim((1.0, 0.0))
    scene.set_clim((0.2, 0.9))
    assert scene.colour_range() == (0.2, 0.9)
    scene.set_clim(None)
    assert scene.colour_range() == (0.0, 1.0)


def test_element_info_of_a_curve_vertex_lists_degree_and_values():
    scene = Scene()
    layer = scene.set_curve(_y_curve())
    layer.add_scalar_quantity("smoothness", [math.nan, 1.0, math.nan, math.nan, math.nan], location="vertices")
    info = scene.element_info("curve", "vertices", 0)
    assert info["degree"] == 3 and math.isnan(info["values"]["smoothness"])
    text = format_element_info(info)
    assert "curve vertex #0" in text and "degree = 3" in text and "nan (invalid)" in text


def test_summary_cells_show_scores_with_counts_in_the_papers_layout():
    summary = {
        "topology": {"bottleneck": 0.0123, "wasserstein": 0.00456, "eps_star": 0.02, "n_bars": 7},
        "boundedness": {"skeletal": 0.9, "curve": 1.0},
        "centeredness": {"skeletal": 0.85, "curve": math.nan},
        "smoothness": {"skeletal": 0.7, "curve": None},
        "counts": {
            "boundedness": {"skeletal": 100, "curve": 200},
            "centeredness": {"skeletal": 100, "curve": 0},
            "smoothness": {"skeletal": 98, "curve": 0},
        },
    }
    cells = summary_cells(summary)
    assert cells[0] == ["0.0123 / 0.0046", "—"]
    assert cells[1] == ["0.900  (n = 100)", "1.000  (n = 200)"]
    assert cells[2][1] == "nan  (n = 0)"
    assert cells[3] == ["0.700  (n = 98)", "—"]
    assert summary_cells(None)[1] == ["—", "—"]
