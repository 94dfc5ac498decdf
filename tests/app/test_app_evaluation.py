"""A real evaluation in the window's worker thread: it completes and fills the panels, Cancel stops a
long one with no result landing, thresholds re-score without recomputing, exports reload."""

from __future__ import annotations

import csv
import json
import os

import numpy as np
import pytest
from PySide6 import QtCore

import skelcore
from skelcore import shapes
from shape_files import write_shape_files
from skelcore.io import load_any, write_points_ply
from skelcore.params import Params

pytestmark = [pytest.mark.gui, pytest.mark.window(auto_evaluate=True, dialogs="record")]


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    return write_shape_files(tmp_path_factory.mktemp("y"), shapes.y_shape(1500, seed=3))


@pytest.fixture(scope="module")
def evaluation(files):
    """One real evaluation of the files, shared by the tests that only need its result."""
    from skelcore.io import load_cloud, load_curve, load_points

    return skelcore.evaluate(load_cloud(files["cloud"]), load_points(files["skeletal"]), load_curve(files["curve"]),
                             inputs=dict(files))


@pytest.fixture
def evaluated(window, files, evaluation, monkeypatch):
    """The window with the three files loaded and their evaluation shown; evaluating again fails."""
    window.session.auto_evaluate = False
    window.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    window.session._evaluated_layers = (window.scene.cloud, window.scene.skeletal, window.scene.curve)
    window.session._task_succeeded("evaluation", evaluation)
    monkeypatch.setattr(skelcore, "evaluate", lambda *a, **k: pytest.fail("recomputed"))
    return window


def test_loading_inputs_runs_one_evaluation_in_the_worker_and_fills_the_panels(window, files, qtbot, monkeypatch):
    calls = []
    real = skelcore.evaluate

    def counting(*args, **kwargs):
        calls.append(1)
        return real(*args, **kwargs)

    monkeypatch.setattr(skelcore, "evaluate", counting)
    with qtbot.waitSignal(window.session.evaluated, timeout=60000):
        window.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    w = window
    ev = w.scene.evaluation
    assert ev is not None and len(calls) == 1
    summary = ev.summary()
    assert w.summary.cell_text("boundedness", "skeletal points") == (
        f"{summary['boundedness']['skeletal']:.3f}  (n = {summary['counts']['boundedness']['skeletal']:,})"
    )
    assert w.summary.cell_text("d_B / d_Wp", "skeletal points").startswith(f"{summary['topology']['bottleneck']:.4f}")
    assert w.summary.cell_text("smoothness", "curve skeleton").endswith(f"(n = {summary['counts']['smoothness']['curve']:,})")
    w.docks["Barcodes"].raise_()
    qtbot.waitUntil(lambda: "d_B" in w.barcodes.title(), timeout=30000)
    title = w.barcodes.title()
    assert "d_B" in title and "d_Wp" in title and f"K = {ev.topology.n_bars}" in title
    bar_axes = w.barcodes.figure.axes
    assert len(bar_axes) == 2 and all(len(ax.collections) >= 1 for ax in bar_axes)
    w.docks["Histogram"].raise_()
    qtbot.waitUntil(lambda: w.histogram.threshold is not None, timeout=30000)
    assert w.histogram.threshold == pytest.approx(w.scene.beta_star)
    assert not w.progress.isVisible() and not w.session.runner.running
    assert w.scene.skeletal.quantities["boundedness"].values.shape == (1500,)
    assert w.scene.curve.samples is not None


def test_thresholds_change_the_summary_at_once_without_recomputing(evaluated):
    w = evaluated
    before = w.summary.cell_text("boundedness", "skeletal points")
    c_before = w.scene.skeletal.quantities["centeredness"].values.copy()
    w.summary.beta_star.setValue(1.0)  # nothing is > 1: every element unbounded, centeredness 0
    assert w.summary.cell_text("boundedness", "skeletal points") == "0.000  (n = 1,500)"
    assert w.summary.cell_text("boundedness", "skeletal points") != before
    assert np.all(w.scene.skeletal.quantities["centeredness"].values == 0.0)
    assert not np.array_equal(c_before, w.scene.skeletal.quantities["centeredness"].values)
    w.summary.c_star.setValue(0.0)
    assert w.scene.summary()["centeredness"]["skeletal"] == 0.0
    assert not w.session.runner.running


def test_the_settings_parameters_are_one_object_until_a_choice_or_threshold_changes(evaluated):
    """The window asks for its parameters several times per edit: the same object while nothing
    changed, a new one (with the change) after a setting or a threshold moved; the staleness test
    compares every parameter but the thresholds, as a copy with the shown thresholds would."""
    from skelscope.session import same_but_thresholds

    w = evaluated
    first = w.session.params()
    assert w.session.params() is first and w.settings_panel.params() is w.settings_panel.params()
    assert w.session.stale_reason() == ""
    w.summary.beta_star.setValue(0.5)
    moved = w.session.params()
    assert moved is not first and moved.beta_star == 0.5 and w.session.stale_reason() == ""
    w.settings_panel.tangent_k.setValue(w.settings_panel.tangent_k.value() + 2)
    assert w.session.params().tangent_k == moved.tangent_k + 2 and w.session.stale_reason() == "settings changed"
    w.settings_panel.tangent_k.setValue(w.settings_panel.tangent_k.value() - 2)
    assert w.session.params() == moved and w.session.stale_reason() == ""
    base = Params()
    for change in ({}, {"beta_star": 0.3}, {"c_star": 0.1, "beta_star": 0.9}, {"tangent_k": 7},
                   {"k_center": 11, "c_star": 0.2}, {"eps_quantile": 0.5}):
        other = base.replace(**change)
        assert same_but_thresholds(base, other) == (other.replace(beta_star=base.beta_star, c_star=base.c_star) == base)


def test_cancel_stops_a_long_evaluation_and_no_result_lands(window, files, qtbot):
    w = window
    w.session.auto_evaluate = False
    w.settings_panel.boundedness_method.setCurrentText("paper")  # the reference tool's slow estimator
    w.session.load_files([files["cloud"], files["skeletal"]])
    stages = []
    w.session.runner.progressed.connect(lambda f, s: stages.append(s))
    assert w.session.start_evaluation()
    qtbot.waitUntil(lambda: "skeletal boundedness" in stages, timeout=30000)
    assert w.progress.isVisible() and w.cancel_button.isVisible()
    task = w.session.runner._current
    with qtbot.waitSignal(w.session.runner.cancelled, timeout=10000):
        w.cancel_button.click()
    assert task.wait(10000)
    qtbot.wait(100)
    assert w.scene.evaluation is None and not w.session.runner.running
    assert not w.progress.isVisible()
    assert w.dialogs == []


def test_the_summary_says_an_evaluation_was_cancelled_and_how_to_run_it_again(window, files, qtbot):
    w = window
    w.session.auto_evaluate = False
    w.settings_panel.boundedness_method.setCurrentText("paper")  # slow enough to cancel
    assert "load a cloud and a skeleton" in w.summary.details.text()
    w.session.load_files([files["cloud"], files["skeletal"]])
    assert "Not evaluated yet" in w.summary.details.text() and "F5" in w.summary.details.text()
    assert w.session.start_evaluation()
    assert "Evaluating" in w.summary.details.text()
    task = w.session.runner._current
    cancel = w.actions_by_name["cancel"]
    assert cancel.isEnabled() and cancel.shortcut().toString() == "Esc"
    cancel.trigger()
    assert not w.session.runner.running
    text = w.summary.details.text()
    assert "cancelled" in text and "Evaluate (F5)" in text and "load a cloud" not in text
    assert task.wait(20000)
    w.session.close_layer("skeletal")  # no longer evaluable: what to load
    assert "load a cloud and a skeleton" in w.summary.details.text()
    assert w.dialogs == []


def test_loading_new_inputs_during_a_run_drops_its_result(window, files, qtbot, tmp_path):
    w = window
    w.session.auto_evaluate = False
    w.session.load_files([files["cloud"], files["skeletal"]])
    w.session.start_evaluation(Params(boundedness_method="paper"))
    old = w.session.runner._current
    w.session.load_as("curve", files["curve"])  # inputs changed: the old run is cancelled and ignored
    assert old.wait(20000)
    qtbot.wait(100)
    assert w.scene.evaluation is None and not w.session.runner.running


def test_an_invalid_evaluation_input_becomes_a_dialog(window, files, qtbot, tmp_path, monkeypatch):
    # (a skeletal set of another size is not one: tests/app/test_app_trust.py)
    def refuse(*args, **kwargs):
        raise skelcore.SkelInputError("skeletal point set: not what the engine accepts")

    monkeypatch.setattr(skelcore, "evaluate", refuse)
    w = window
    w.session.auto_evaluate = False
    w.session.load_as("cloud", files["cloud"])
    w.session.load_as("skeletal", files["skeletal"])
    with qtbot.waitSignal(w.session.runner.finished, timeout=20000):
        w.session.start_evaluation()
    assert len(w.dialogs) == 1 and "not what the engine accepts" in w.dialogs[0]
    assert w.isVisible() and w.scene.evaluation is None


def test_every_export_reloads(evaluated, tmp_path):
    w = evaluated
    out = tmp_path / "out"
    out.mkdir()
    w.scene.set_metric("smoothness")
    plys = w.export_ply(str(out / "ply"))
    # named after the data: a second dataset exported into the same folder cannot overwrite these
    assert {os.path.basename(p) for p in plys} == {"y_cloud_skeletal.ply", "y_cloud_curve.ply", "y_cloud_curve_samples.ply"}
    assert sorted(os.listdir(out / "ply")) == sorted(os.path.basename(p) for p in plys)  # no staging left
    skel = load_any(out / "ply" / "y_cloud_skeletal.ply")
    assert skel.kind == "points" and np.allclose(skel.points, w.scene.skeletal.points)
    curve = load_any(out / "ply" / "y_cloud_curve.ply")
    assert curve.kind == "curve" and np.array_equal(curve.curve.edges, w.scene.curve.curve.edges)
    samples = load_any(out / "ply" / "y_cloud_curve_samples.ply")
    assert np.allclose(samples.points, w.scene.curve.samples)

    written = w.export_results(str(out / "run.json"))
    doc = json.loads((out / "run.json").read_text())
    assert doc["boundedness"]["skeletal"] == pytest.approx(w.scene.summary()["boundedness"]["skeletal"])
    assert doc["counts"]["smoothness"]["curve"] == w.scene.summary()["counts"]["smoothness"]["curve"]
    with open(out / "run_skeletal.csv") as fh:
        rows = list(csv.DictReader(fh))
    assert len(rows) == 1500 and float(rows[7]["x"]) == pytest.approx(w.scene.skeletal.points[7, 0])
    with open(out / "run_curve_vertices.csv") as fh:
        vertex_rows = list(csv.DictReader(fh))
    assert sum(r["smoothness"] == "nan" for r in vertex_rows) == 4  # the Y's junction and three tips
    with open(out / "run_barcodes.csv") as fh:
        bars = list(csv.DictReader(fh))
    assert {r["diagram"] for r in bars} == {"cloud", "skeletal"} and any(r["death"] == "inf" for r in bars)
    assert len(written) == 6  # + run_cloud.csv, the coverage gap per cloud point

    png = w.save_screenshot(str(out / "view.png"), scale=2)
    from matplotlib.image import imread

    img = imread(png)
    view = w.view.widget
    assert img.shape[0] == 2 * view.height() and img.shape[1] == 2 * view.width()
    assert img[..., :3].std() > 0.02
    transparent = imread(w.save_screenshot(str(out / "clear.png"), transparent=True))
    assert transparent.shape[2] == 4 and transparent[..., 3].min() == 0 and transparent[..., 3].max() == 1


def test_exports_never_overwrite_a_loaded_input(evaluated, files):
    w = evaluated
    before = open(files["cloud"], "rb").read()
    with pytest.raises(skelcore.SkelInputError, match="refusing to overwrite"):
        w.save_screenshot(files["cloud"])
    w._guarded("Screenshot", w.save_screenshot, files["cloud"])
    assert w.dialogs and "refusing to overwrite" in w.dialogs[-1]
    assert open(files["cloud"], "rb").read() == before


def test_a_landing_result_is_shown_in_separate_event_loop_turns(window, files, evaluation, qtbot, monkeypatch):
    """The panels' repaint, the 3D frame, the barcode artists and their drawing each get their own
    turn of the event loop (a 1 ms timer fires between each two), so the window's stalls do not add up."""
    w = window
    w.session.auto_evaluate = False
    w.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    w.docks["Barcodes"].raise_()
    w.barcodes.prepare()
    qtbot.waitUntil(lambda: not w.view.render_pending and not w.barcodes.draw_pending, timeout=30000)
    events: list[str] = []

    class PaintSpy(QtCore.QObject):
        def eventFilter(self, obj, event):  # noqa: N802
            if event.type() == QtCore.QEvent.Type.Paint:
                events.append("summary painted")
            return False

    spy = PaintSpy()
    w.summary.table.viewport().installEventFilter(spy)
    w.view.plotter.ren_win.AddObserver("EndEvent", lambda *a: events.append("frame"))
    show = w.barcodes.show_topology
    monkeypatch.setattr(w.barcodes, "show_topology", lambda topology: (events.append("artists"), show(topology)))
    w.barcodes.drawn.connect(lambda: events.append("drawn"))
    beat = QtCore.QTimer()
    beat.setInterval(1)
    beat.timeout.connect(lambda: events.append("beat"))
    beat.start()
    w.session._evaluated_layers = (w.scene.cloud, w.scene.skeletal, w.scene.curve)
    w.session._task_succeeded("evaluation", evaluation)
    events.append("delivered")
    qtbot.waitUntil(lambda: "drawn" in events, timeout=10000)
    beat.stop()
    assert "d_B" in w.barcodes.title()
    steps = ["delivered", "summary painted", "frame", "artists", "drawn"]
    at = [events.index(step) for step in steps]
    assert at == sorted(at), events
    for i in range(1, len(steps) - 1):  # Qt repaints the changed panels right after the delivery
        assert "beat" in events[at[i] + 1:at[i + 1]], f"no event-loop turn between {steps[i]} and {steps[i + 1]}: {events}"


def test_barcodes_drawn_in_stages_give_the_same_pixels_as_one_draw(evaluation, qtbot):
    from skelscope.panels.barcode import BarcodePanel

    panel = BarcodePanel()
    qtbot.addWidget(panel)
    panel.resize(420, 440)
    panel.show()
    qtbot.waitExposed(panel)
    panel.prepare()
    panel.show_topology(evaluation.topology)
    with qtbot.waitSignal(panel.drawn, timeout=30000):
        panel.draw_now()  # the first of two stages now, the second in a later event-loop turn
    staged = np.asarray(panel.canvas.renderer.buffer_rgba()).copy()
    panel.canvas.draw()  # matplotlib's own whole-figure draw
    assert np.array_equal(staged, np.asarray(panel.canvas.renderer.buffer_rgba()))
    assert (staged[..., :3] < 100).any()  # the bars are there, not a blank figure
