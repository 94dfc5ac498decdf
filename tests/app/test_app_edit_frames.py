"""The frames of an edit (docs/guide/viewer.md "Editing the curve skeleton", docs/performance.md 6.10):
the first phase is already running when the edited curve is swapped in and redrawn (and is kept, not
dropped as a change of inputs); when its scores land the recoloured frame is drawn at once, the
Defects dock says "updating" from that moment, and no further frame follows until the second phase
lands. The shape: the cylinder with a twig of test_app_editing."""

from __future__ import annotations

import pytest

from skelscope.view.frames import RENDER_DELAY_MS
from test_app_edit_phases import held, prune_tip_to_second_phase  # noqa: F401 - the fixture
from test_app_editing import key, loaded, wait_evaluated

pytestmark = [pytest.mark.gui, pytest.mark.window(questions="default")]


def test_the_first_phase_runs_while_the_edited_curve_is_redrawn(window, qtbot, tmp_path):
    from skelscope.scene import SceneEvent

    w = window
    _cloud, _curve, tip = loaded(qtbot, w, tmp_path)
    at_swap: list[tuple[str | None, object]] = []

    def on_scene(event: SceneEvent) -> None:
        if event.kind == "layer" and event.layer == "curve":
            at_swap.append((w.session.runner.current_name, w.session.runner._current))

    w.scene.subscribe(on_scene)
    key(qtbot, w, "E")
    w.select_element("curve", "vertices", tip)
    key(qtbot, w, "Delete")
    task = w.session.runner._current
    assert at_swap == [("evaluation", task)]  # started before the swap, the same task after it
    assert w.edits.last_scoring == "update"
    wait_evaluated(qtbot, w)
    assert w.scene.evaluation is not None and w.scene.evaluation.curve.curve is w.scene.curve.curve


def test_the_recoloured_frame_comes_at_once_and_alone(window, qtbot, tmp_path, held):  # noqa: F811
    from skelscope.edit_scoring import UPDATING

    w = window
    _cloud, _curve, tip = loaded(qtbot, w, tmp_path)
    frames: list[int] = []
    w.view.plotter.ren_win.AddObserver("EndEvent", lambda *_a: frames.append(1))
    seen: dict[str, object] = {}

    def landed(_ev: object) -> None:  # the first phase's scores in the scene, before its frame
        seen["frames"] = len(frames)
        seen["pending"] = w.defects.panel.pending

    w.session.scores_shown.connect(landed)
    prune_tip_to_second_phase(qtbot, w, tip)
    qtbot.waitUntil(lambda: "frames" in seen, timeout=30000)
    assert seen["pending"] == UPDATING  # the dock says "updating" as the scores land, never "cancelled"
    assert len(frames) == seen["frames"] + 1  # the recoloured frame, drawn in the same turn
    assert not w.view.render_pending
    qtbot.wait(400)  # the second phase held: nothing else to draw
    assert len(frames) == seen["frames"] + 1 and w.defects.panel.pending == UPDATING
    held.set()
    wait_evaluated(qtbot, w)
    qtbot.waitUntil(lambda: not w.view.render_pending, timeout=10000)
    assert len(frames) >= seen["frames"] + 2 and not w.defects.panel.pending  # the defects' frame


def test_an_empty_defect_overlay_cleared_or_shown_again_asks_for_no_frame(window, qtbot, tmp_path):
    """Refreshing a Defects dock with nothing drawn (an edit's first phase) costs no frame; clearing
    drawn defects does."""
    w = window
    loaded(qtbot, w, tmp_path)
    overlay = w.defects.overlay
    qtbot.waitUntil(lambda: not w.view.render_pending, timeout=10000)
    assert overlay.names  # the twig's defects drawn
    overlay.set_visible(w.defects.visible)  # as they are: nothing changes
    assert not w.view.render_pending
    overlay.clear()
    assert w.view.render_pending
    qtbot.waitUntil(lambda: not w.view.render_pending, timeout=10000)
    overlay.clear()
    overlay.set_visible(True)
    assert not w.view.render_pending


def test_a_cancelled_first_phase_lets_the_edited_curve_be_drawn_at_once(window, qtbot, tmp_path, monkeypatch):
    """Esc while an edit's scores are computed: the view's hold (FRAME_HOLD_S) ends with the task, so the
    edited curve is drawn at the next frame, uncoloured."""
    import threading

    import skelscope.session as session

    w = window
    _cloud, _curve, tip = loaded(qtbot, w, tmp_path)
    entered = threading.Event()

    def scores_job(base, curve):
        def job(progress, cancel):
            from skelcore.errors import Cancelled

            entered.set()
            while not cancel():
                threading.Event().wait(0.01)
            raise Cancelled("cancelled")

        return job

    monkeypatch.setattr(session, "scores_job", scores_job)
    key(qtbot, w, "E")
    w.select_element("curve", "vertices", tip)
    key(qtbot, w, "Delete")
    assert entered.wait(30) and w.view._frames._held_until > 0  # held for the scores
    key(qtbot, w, "Escape")
    assert not w.session.runner.running and w.view._frames._held_until == 0.0
    qtbot.waitUntil(lambda: not w.view.render_pending, timeout=10000)
    assert w.scene.evaluation is None and w.scene.curve.edited


def test_an_edit_keeps_the_curves_actors_and_swaps_their_points(window, qtbot, tmp_path):
    """The edited curve goes into the actors already built (no pyvista actor made or removed on the way
    to the recoloured frame, the colour bar hidden meanwhile, not made again): each shows the new curve's vertices, samples and edges, and a pick finds
    the new curve's elements, never a sample of the curve before."""
    import numpy as np

    w = window
    _cloud, _curve, tip = loaded(qtbot, w, tmp_path)
    view = w.view
    names = ("curve-vertices", "curve-samples", "curve-edges")
    before = {n: view._actors[n] for n in names}
    curve_props = sorted(n for n in view.plotter.renderer.actors if n.startswith("curve"))
    old_samples = w.scene.curve.samples.copy()
    bar = view.plotter.scalar_bars[w.scene.metric]
    key(qtbot, w, "E")
    w.select_element("curve", "vertices", tip)
    key(qtbot, w, "Delete")
    assert "curve-samples" not in view._actors and "curve-samples" not in view._pickable  # not scored yet
    assert not bar.GetVisibility()  # nothing coloured: hidden, not removed
    wait_evaluated(qtbot, w)
    layer = w.scene.curve
    assert {n: view._actors[n] for n in names} == before
    assert view.plotter.scalar_bars[w.scene.metric] is bar and bar.GetVisibility()
    assert sorted(n for n in view.plotter.renderer.actors if n.startswith("curve")) == curve_props
    np.testing.assert_allclose(view._meshes["curve-vertices"].points, layer.points, rtol=1e-6)
    np.testing.assert_allclose(view._meshes["curve-samples"].points, layer.samples, rtol=1e-6)
    assert len(layer.samples) != len(old_samples)  # the twig's samples went with it
    assert view._actors["curve-edges"].mapper.dataset.n_lines == len(layer.edges)
    assert view._actors["curve-samples"].GetVisibility() and view._actors["curve-vertices"].GetVisibility()
    qtbot.waitUntil(lambda: not view.render_pending, timeout=10000)
    for xyz in (layer.points[3], layer.samples[7]):
        info = view.pick_display(*view.world_to_display(xyz))  # what is drawn there: the new curve's
        assert info is not None and info["layer"] == "curve"
        drawn = layer.points if info["location"] == "vertices" else layer.samples
        np.testing.assert_allclose(info["xyz"], drawn[info["index"]], atol=1e-12)
        assert np.linalg.norm(np.subtract(view.world_to_display(info["xyz"]), view.world_to_display(xyz))) < 8


def test_an_edits_key_gives_the_curves_actors_their_new_points_once(window, qtbot, tmp_path):
    """The curve replaced clears its evaluation before its "layer" event: the view recolours a
    replaced layer's actors at that event only, so the key swaps the new vertices in once, not twice."""
    w = window
    _cloud, _curve, tip = loaded(qtbot, w, tmp_path)
    view = w.view
    swapped: list[str] = []
    swap = view._swap_points
    view._swap_points = lambda key, *a, **k: swapped.append(key) or swap(key, *a, **k)
    key(qtbot, w, "E")
    w.select_element("curve", "vertices", tip)
    key(qtbot, w, "Delete")
    assert swapped == ["curve-vertices"]  # the samples come with the scores
    assert view._sources["curve-vertices"] is w.scene.curve.points
    wait_evaluated(qtbot, w)
    assert swapped[:2] == ["curve-vertices", "curve-samples"]  # the scores' samples (the defects' after them)


def test_the_window_repaints_wait_with_the_held_frames(window, qtbot):
    """While the view holds its frames (an edit's scores on their way) the window's other repaints
    wait too (skelscope.view.paint_hold: each composes the whole window); the release, a hold that
    runs out, or the held frame drawn at once paints them."""
    from PySide6 import QtCore

    w = window
    bar = w.statusBar()
    painted: list[int] = []

    class Count(QtCore.QObject):
        def eventFilter(self, obj, event):  # noqa: N802
            if event.type() == QtCore.QEvent.Type.Paint:
                painted.append(1)
            return False

    counter = Count()
    bar.installEventFilter(counter)
    frames: list[int] = []
    w.view.plotter.ren_win.AddObserver("EndEvent", lambda *_a: frames.append(1))
    qtbot.waitUntil(lambda: not w.view.render_pending, timeout=10000)
    qtbot.wait(50)
    for end in ("release", "runs out", "draw now"):
        painted.clear()
        frames.clear()
        w.view.hold_frames(0.3 if end == "runs out" else 30.0)
        w.view.request_render()
        bar.showMessage(f"held: {end}")
        qtbot.wait(150)
        assert not painted and not frames, end  # neither the message nor the frame yet
        if end == "release":
            w.view.release_frames()
        elif end == "draw now":
            w.view.draw_now()
            assert painted and frames  # in the same call: one repaint of the window paints both
        qtbot.waitUntil(lambda: bool(painted and frames) and not w.view.render_pending, timeout=5000)
    for end in ("release", "runs out"):  # held with no frame asked: the window repaints at the hold's end
        painted.clear()
        w.view.hold_frames(30.0 if end == "release" else 0.3)
        bar.showMessage(f"held, no frame: {end}")
        qtbot.wait(100)
        assert not painted, end
        if end == "release":
            w.view.release_frames()
        qtbot.waitUntil(lambda: bool(painted), timeout=5000)
    bar.removeEventFilter(counter)


def test_a_frame_after_a_held_one_drawn_at_once_comes_without_the_holds_delay(window, qtbot):
    """A frame that waited in a hold (its timer restarted for the hold's remainder), then drawn at once
    (an edit's scores landing): the next frame asked for comes after the usual delay, not the hold's
    remainder (QTimer.start(ms) kept it as the timer's interval: the second phase's frame came a
    second late)."""
    import time

    w = window
    frames: list[float] = []
    w.view.plotter.ren_win.AddObserver("EndEvent", lambda *_a: frames.append(time.perf_counter()))
    qtbot.waitUntil(lambda: not w.view.render_pending, timeout=10000)
    w.view.hold_frames(5.0)
    w.view.request_render()
    qtbot.wait(100)  # the frame's timer fired in the hold and waits for its remainder
    assert not frames
    w.view.draw_now()
    assert len(frames) == 1
    asked = time.perf_counter()
    w.view.request_render()
    qtbot.waitUntil(lambda: len(frames) == 2, timeout=10000)
    assert w.view._frames._timer.interval() == RENDER_DELAY_MS  # not the hold's remainder (4.9 s)
    assert frames[1] - asked < 2.45  # well before the remainder's 4.9 s, whatever the machine's load


def test_an_edits_task_widgets_show_after_its_recoloured_frame(window, qtbot, tmp_path, held):  # noqa: F811
    """The status bar's stage, progress and Cancel button of an edit's scoring are laid out after the
    recoloured frame (the held repaint would show them only then), not beside the first phase; Esc
    cancels meanwhile; a plain evaluation shows them at once (test_app_evaluation)."""
    w = window
    _cloud, _curve, tip = loaded(qtbot, w, tmp_path)
    at_frame: list[bool] = []
    w.session.scores_shown.connect(lambda _ev: w.view.after_render(lambda: at_frame.append(w.cancel_button.isVisible())))
    key(qtbot, w, "E")
    w.select_element("curve", "vertices", tip)
    key(qtbot, w, "Delete")
    assert w.session.runner.running and w.actions_by_name["cancel"].isEnabled()
    assert not w.cancel_button.isVisible() and not w.progress.isVisible()
    qtbot.waitUntil(lambda: bool(at_frame), timeout=30000)
    assert at_frame == [False]  # not inside the frame's paint
    qtbot.waitUntil(lambda: w.cancel_button.isVisible(), timeout=5000)  # the second phase runs (held)
    assert w.stage.isVisible() and w.progress.isVisible()
    held.set()
    wait_evaluated(qtbot, w)
    assert not w.cancel_button.isVisible() and not w.progress.isVisible()
