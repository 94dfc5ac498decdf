"""The frames of an edit (docs/guide/viewer.md "Editing the curve skeleton", docs/performance.md 6.10):
the first phase is already running when the edited curve is swapped in and redrawn (and is kept, not
dropped as a change of inputs). The shape: the cylinder with a twig of test_app_editing."""

from __future__ import annotations

import pytest

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
