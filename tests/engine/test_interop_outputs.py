"""An Evaluation out to other libraries: ``to_frame`` rows hold the local arrays and the
flags the overall scores count, ``to_networkx`` the curve with its values, ``to_open3d`` the curve
coloured as the viewer colours it (skelcore.colors, NaN magenta)."""

from __future__ import annotations

import numpy as np
import pytest

import skelcore
from skelcore import shapes
from skelcore.colors import MAGENTA, map_to_rgb
from skelcore.interop.open3d_out import curve_lines


@pytest.fixture(scope="module")
def ev():
    sh = shapes.y_shape(1500, seed=4)
    radius = np.linspace(0.3, 0.1, len(sh.curve_vertices))
    curve = skelcore.CurveSkeleton.from_raw(sh.curve_vertices, sh.curve_edges, radius=radius)
    return skelcore.evaluate(sh.cloud, skeletal=sh.skeletal, curve=curve)


def test_skeletal_frame_holds_the_local_values_and_its_flags_give_the_overall_scores(ev):
    pytest.importorskip("pandas")
    df = ev.to_frame("skeletal")
    s, summ, p = ev.skeletal, ev.summary(), ev.params
    assert len(df) == len(s.points)
    np.testing.assert_array_equal(df[["x", "y", "z"]].to_numpy(), s.points)
    np.testing.assert_array_equal(df["boundedness"].to_numpy(), s.boundedness)
    np.testing.assert_array_equal(df["centeredness"].to_numpy(), s.centeredness(p.beta_star))
    assert df["bounded"].mean() == pytest.approx(summ["boundedness"]["skeletal"])
    assert df["centered"].mean() == pytest.approx(summ["centeredness"]["skeletal"])
    assert df["smoothness"].mean() == pytest.approx(summ["smoothness"]["skeletal"])  # pandas skips NaN
    assert (df["boundedness_valid"] == np.isfinite(s.boundedness)).all()


def test_curve_frames_and_thresholds(ev):
    pytest.importorskip("pandas")
    samples, verts = ev.to_frame("curve_samples"), ev.to_frame("curve_vertices")
    summ = ev.summary()
    assert samples["bounded"].mean() == pytest.approx(summ["boundedness"]["curve"])
    # curve centeredness counts valid samples only (docs/metrics.md 3)
    assert samples.loc[samples["centeredness_valid"], "centered"].mean() == pytest.approx(summ["centeredness"]["curve"])
    np.testing.assert_array_equal(verts["degree"].to_numpy(), ev.curve.vertex_degree)
    np.testing.assert_array_equal(verts["radius"].to_numpy(), ev.curve.curve.radius)
    strict = ev.to_frame("curve_samples", beta_star=0.99)
    assert strict["bounded"].mean() == pytest.approx(ev.summary(beta_star=0.99)["boundedness"]["curve"])
    cloud = ev.to_frame("cloud")
    assert len(cloud) == len(ev.cloud) and cloud["covered_curve"].dtype == bool
    with pytest.raises(ValueError, match="kind must be one of skeletal, curve_samples"):
        ev.to_frame("edges")


def test_networkx_graph_is_the_curve_with_its_values(ev):
    nx = pytest.importorskip("networkx")
    g = ev.to_networkx()
    c = ev.curve
    assert g.number_of_nodes() == c.curve.n_vertices and g.number_of_edges() == c.curve.n_edges
    assert nx.number_connected_components(g) == 1 and nx.cycle_basis(g) == []
    for i in (0, 5, c.curve.n_vertices - 1):
        node = g.nodes[i]
        np.testing.assert_array_equal(node["pos"], c.curve.vertices[i])
        assert node["degree"] == c.vertex_degree[i] and node["radius"] == c.curve.radius[i]
        assert node["smoothness"] == pytest.approx(c.vertex_smoothness[i], nan_ok=True)
    a, b = c.curve.edges[3]
    on = c.sample_edge == 3
    assert g.edges[a, b]["n_samples"] == on.sum()
    assert g.edges[a, b]["boundedness"] == pytest.approx(np.nanmean(c.sample_boundedness[on]))
    assert g.graph["summary"]["boundedness"] == ev.summary()["boundedness"]


def test_curve_lines_are_coloured_like_the_viewer_with_magenta_for_invalid(ev):
    points, lines, colours = curve_lines(ev, "smoothness")
    c = ev.curve
    # every edge halved: each half takes its nearer vertex's colour
    assert len(lines) == 2 * c.curve.n_edges
    expected = map_to_rgb(c.vertex_smoothness[c.curve.edges.ravel(order="F")], 0.0, 1.0)
    np.testing.assert_array_equal(colours, expected)
    ends = c.vertex_degree == 1  # smoothness is NaN there (docs/metrics.md 4)
    assert ends.any()
    end_halves = np.isin(lines[:, 0], np.flatnonzero(ends))
    assert (colours[end_halves] == MAGENTA).all()
    pts, lines, colours = curve_lines(ev, "boundedness")
    assert len(pts) > c.curve.n_vertices + len(c.samples) - 1 and colours.dtype == np.uint8
    with pytest.raises(ValueError, match="metric must be one of"):
        curve_lines(ev, "topology")


def test_to_open3d_is_a_lineset_with_the_viewer_colours(ev):
    o3d = pytest.importorskip("open3d")
    ls = ev.to_open3d("centeredness")
    assert isinstance(ls, o3d.geometry.LineSet)
    points, lines, colours = curve_lines(ev, "centeredness")
    np.testing.assert_array_equal(np.asarray(ls.points), points)
    np.testing.assert_array_equal(np.asarray(ls.lines), lines)
    np.testing.assert_allclose(np.asarray(ls.colors) * 255.0, colours, atol=1e-9)
