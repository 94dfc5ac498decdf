"""Long work at 1M points: Cancel frees the window at once and the worker stops; quitting while a
task runs cancels it and the process exits 0 without Qt's "Destroyed while thread" abort (at the
smallest size evaluated in a child process: its start and its frames cost the test nothing else)."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

import numpy as np
import pytest

from skelcore import shapes

pytestmark = pytest.mark.gui

ROOT = Path(__file__).resolve().parents[2]
MILLION = 1_000_000


@pytest.fixture(scope="module")
def million():
    cloud = shapes.sphere_surface(MILLION, seed=0)
    return cloud, cloud * 0.05  # a skeletal set in pointwise correspondence (the cloud contracted)


def test_cancel_during_a_million_point_evaluation_stops_the_worker_and_the_window_survives(window, qtbot, million):
    w = window
    cloud, skeletal = million
    with w.session.batch():
        w.scene.set_cloud(cloud)
        w.scene.set_skeletal(skeletal)
    stages = []
    w.session.runner.progressed.connect(lambda f, s: stages.append(s))
    assert w.session.start_evaluation()
    task = w.session.runner._current
    qtbot.waitUntil(lambda: bool(stages), timeout=60000)
    qtbot.waitUntil(lambda: w.stage.text() == stages[-1], timeout=30000)  # the label names the running stage
    assert w.cancel_button.isVisible()
    w.cancel_button.click()
    # At once: the window is idle, no result can land, Evaluate is available again.
    assert not w.session.runner.running and not w.cancel_button.isVisible()
    assert w.actions_by_name["evaluate"].isEnabled()
    assert task.is_cancelled()
    assert task.wait(120000), "the worker never reached a checkpoint"
    qtbot.wait(50)
    assert w.scene.evaluation is None and w.isVisible()
    assert "cancelled" in w.statusBar().currentMessage()


_QUIT_SCRIPT = textwrap.dedent(r"""
    import sys, time
    from PySide6 import QtCore, QtWidgets
    app = QtWidgets.QApplication(["skelscope-quit-test"])
    from skelscope.__main__ import _exited
    from skelscope.main_window import MainWindow
    from skelcore import shapes

    w = MainWindow(settings=QtCore.QSettings(sys.argv[1], QtCore.QSettings.Format.IniFormat))
    w.session.auto_evaluate = False
    cloud = shapes.sphere_surface(int(sys.argv[2]), seed=0)
    with w.session.batch():
        w.scene.set_cloud(cloud)
        w.scene.set_skeletal(cloud * 0.05)
    w.show()

    def quit_while_running():
        print(f"running at quit: {w.session.runner.running}", flush=True)
        print(f"engine process: {getattr(w.session.runner._current, 'pid', None)}", flush=True)
        print(f"quit at {time.monotonic():.3f}", flush=True)
        w.actions_by_name["quit"].trigger()  # Ctrl+Q

    def first_progress(fraction, stage):
        if not getattr(first_progress, "done", False):
            first_progress.done = True
            QtCore.QTimer.singleShot(300, quit_while_running)

    w.session.runner.progressed.connect(first_progress)
    QtCore.QTimer.singleShot(100, w.session.start_evaluation)
    sys.exit(_exited(app.exec()))
""")


def test_quitting_while_an_evaluation_in_a_child_process_runs_exits_0_without_a_qthread_abort(tmp_path):
    """The cloud and its skeletal set of PROCESS_FROM points together: the least the window evaluates
    in a child process, read by a thread of its own (a 1M cloud made the same checks draw and send a
    million points); the quit lands 0.3 s after the first progress, and the test fails if the
    evaluation was no longer running then."""
    from skelscope.session import PROCESS_FROM

    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, "-c", _QUIT_SCRIPT, str(tmp_path / "s.ini"), str(PROCESS_FROM // 2)],
                         capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)
    assert "running at quit: True" in out.stdout, out.stdout + out.stderr
    assert out.returncode == 0, out.stderr
    # the evaluation ran in a child process, which does not outlive the window
    pid = int(out.stdout.split("engine process: ")[1].split()[0])
    deadline = time.monotonic() + 10
    while _alive(pid) and time.monotonic() < deadline:
        time.sleep(0.05)
    assert not _alive(pid)
    assert "Destroyed while thread" not in out.stderr and "QThread" not in out.stderr
    assert "Traceback" not in out.stderr


def _alive(pid: int) -> bool:
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().split(")")[-1].split()[0] != "Z"  # a zombie has ended
    except FileNotFoundError:
        return False


# ---- every stage, the stage label, a bounded quit (long work) --------------------------------

_STAGES = ("topology", "skeletal boundedness", "skeletal centeredness", "skeletal smoothness", "curve boundedness",
           "curve centeredness", "curve smoothness", "skeletal coverage", "curve coverage")


@pytest.mark.parametrize("target", _STAGES)
def test_cancel_inside_each_stage_stops_the_engine_there_and_the_window_survives(window, qtbot, monkeypatch, target):
    """The real engine on a Y with a skeletal set and a curve; its progress report holds the worker
    inside ``target`` until the window's Cancel is pressed, so the cancel lands in that very stage."""
    import skelcore
    from skelcore.curve import CurveSkeleton
    from skelcore.errors import Cancelled

    real = skelcore.evaluate
    seen: list[str] = []
    raised: list[BaseException] = []

    def paused_in_target(cloud, skeletal, curve, params, progress, cancel, **kwargs):
        def report(fraction, stage):
            seen.append(stage)
            progress(fraction, stage)
            while stage == target and not cancel():  # the stage's work resumes once Cancel is pressed
                time.sleep(0.005)

        try:
            return real(cloud, skeletal, curve, params, report, cancel, **kwargs)
        except Cancelled as exc:
            raised.append(exc)
            raise

    monkeypatch.setattr(skelcore, "evaluate", paused_in_target)  # read when the task starts
    w = window
    sh = shapes.y_shape(600, seed=0)
    with w.session.batch():
        w.scene.set_cloud(sh.cloud)
        w.scene.set_skeletal(sh.skeletal)
        w.scene.set_curve(CurveSkeleton.from_raw(sh.curve_vertices, sh.curve_edges))
    assert w.session.start_evaluation()
    task = w.session.runner._current
    # the label names the stage that runs (with any running beside it)
    qtbot.waitUntil(lambda: target in w.stage.toolTip().split(" + "), timeout=60000)
    assert target in task.stage.split(" + ") and task.isRunning()
    w.cancel_button.click()
    assert not w.session.runner.running and not w.cancel_button.isVisible()
    assert task.wait(60000)
    # stopped in that stage or in one running beside it (the stages run side by side; one beside it may
    # not have shown its label yet), not later: no progress after the target's
    assert len(raised) == 1 and str(raised[0]).startswith("cancelled during ")
    assert seen[-1] == target
    qtbot.wait(50)
    assert w.scene.evaluation is None and w.isVisible() and w.actions_by_name["evaluate"].isEnabled()


def test_the_stage_label_follows_the_stage_that_runs(window, qtbot):
    w = window
    go = [threading.Event() for _ in range(3)]

    def job(progress, cancel):
        for i, stage in enumerate(("topology", "skeletal boundedness", "skeletal coverage")):
            progress(i / 3, stage)
            go[i].wait(30)
        return None

    w.session.runner.start(job, "evaluation")
    for i, stage in enumerate(("topology", "skeletal boundedness", "skeletal coverage")):
        qtbot.waitUntil(lambda s=stage: w.stage.text() == s, timeout=10000)
        go[i].set()
    qtbot.waitUntil(lambda: not w.session.runner.running, timeout=10000)
    assert not w.stage.isVisible()


def test_quitting_waits_for_no_stuck_task_and_keeps_the_settings(window, tmp_path, monkeypatch):
    """A task inside an engine call without a checkpoint (main window and Study dialog both): closing
    cancels and detaches both and waits for neither (waiting made Ctrl+Q take up to SHUTDOWN_WAIT_S
    longer); neither result can land, and the settings are on disk (the process ends with os._exit)."""
    from skelscope.study_dialog import StudyDialog
    from skelscope.worker import Task

    w = window
    release = threading.Event()

    def stuck(progress, cancel):
        progress(0.0, "topology")
        release.wait(60)
        return "late"

    try:
        main_task = w.session.runner.start(stuck, "evaluation")
        study = StudyDialog(w, str(tmp_path / "cloud.ply"))
        w._study_dialog = study
        study.show()
        study_task = study.runner.start(stuck, "study")
        landed: list[str] = []
        w.session.runner.succeeded.connect(lambda name, result: landed.append(name))
        study.runner.succeeded.connect(lambda name, result: landed.append(name))
        asked: list[float | None] = []
        real_wait = Task.wait
        monkeypatch.setattr(Task, "wait", lambda self, ms=None: (asked.append(ms), real_wait(self, ms))[1])
        w._add_recent(str(tmp_path / "cloud.ply"))  # not yet written to disk (QSettings syncs later)
        w.close()
        assert asked == []
        assert main_task.is_cancelled() and study_task.is_cancelled()
        assert not w.session.runner.running and not study.runner.running
        assert not study.isVisible() and not w.isVisible()
        assert "cloud.ply" in (tmp_path / "settings.ini").read_text()  # synced: the process may end with os._exit
    finally:
        release.set()
    assert main_task.wait(10000) and study_task.wait(10000)
    from PySide6 import QtWidgets

    QtWidgets.QApplication.processEvents()
    assert landed == []


def test_the_stage_label_lists_every_stage_running_side_by_side(window, qtbot):
    """Two stages on two lanes report in turn: the label names both, in the order they started, and
    does not flip to whichever reported last."""
    w = window
    go = threading.Event()

    def job(progress, cancel):
        progress.stages(("skeletal boundedness",))
        progress(0.1, "skeletal boundedness")
        progress.stages(("skeletal boundedness", "topology"))
        for i in range(20):
            progress(0.1 + 0.01 * i, ("topology", "skeletal boundedness")[i % 2])
        go.wait(30)
        progress.stages(("topology",))
        progress(0.5, "topology")
        go.clear()
        go.wait(30)

    w.session.runner.start(job, "evaluation")
    qtbot.waitUntil(lambda: w.stage.toolTip() == "skeletal boundedness + topology", timeout=10000)
    assert w.stage.text() == "skeletal boundedness + topology"  # the fixed-width label fits two stages
    qtbot.wait(300)  # reports from both lanes meanwhile: the label stays
    assert w.stage.text() == "skeletal boundedness + topology"
    go.set()
    qtbot.waitUntil(lambda: w.stage.text() == "topology", timeout=10000)
    go.set()
    qtbot.waitUntil(lambda: not w.session.runner.running, timeout=10000)


def test_the_engine_reports_the_stages_running_side_by_side():
    """``evaluate(on_stages=...)``: every change of the running set, each stage in it once it started
    and out of it once done; on two lanes two stages at once."""
    import skelcore

    sh = shapes.y_shape(800, seed=2)
    seen: list[tuple[str, ...]] = []
    ev = skelcore.evaluate(sh.cloud, sh.skeletal, on_stages=seen.append, workers=2)
    assert seen[-1] == ()
    started = {name for names in seen for name in names}
    assert started == {"topology", "skeletal boundedness", "skeletal centeredness", "skeletal smoothness",
                       "skeletal coverage", "skeletal outside", "skeletal missing parts", "stray points"}
    assert max(len(names) for names in seen) == 2
    assert ev.topology is not None


@pytest.mark.window(dialogs="record")
def test_an_evaluation_in_a_child_process_gives_the_threads_result(window, qtbot):
    """Big inputs are evaluated in a child process (here every input: ``process_from = 0``): the same
    Evaluation lands as in the thread, with the running stages in the label."""
    import skelcore

    w = window
    w.session.process_from = 0
    sh = shapes.y_shape(700, seed=3)
    with w.session.batch():
        w.scene.set_cloud(sh.cloud)
        w.scene.set_skeletal(sh.skeletal)
    labels = []
    w.session.runner.progressed.connect(lambda f, s: labels.append(s))
    with qtbot.waitSignal(w.session.evaluated, timeout=120000) as blocker:
        assert w.session.start_evaluation()
        task = w.session.runner._current
        assert task.pid is None or task.pid != os.getpid()
    ev = blocker.args[0]
    assert task.pid is not None and task.pid != os.getpid()
    assert ev.cloud is w.scene.cloud.points  # not sent back: the window's own array
    expected = skelcore.evaluate(sh.cloud, sh.skeletal)
    got, want = ev.scores().flat(), expected.scores().flat()
    got.pop("seconds"), want.pop("seconds")
    assert got.keys() == want.keys() and all(np.isclose(got[k], want[k], equal_nan=True, rtol=0, atol=0) for k in got)
    assert np.array_equal(ev.skeletal.boundedness, expected.skeletal.boundedness)
    assert any(" + " in label for label in labels)  # stages side by side, named together
    assert w.dialogs == [] and w.scene.evaluation is ev


def test_cancel_kills_the_child_process_inside_the_stage(window, qtbot):
    """Cancel in a child-process evaluation: the window is free at once, the child ends inside the
    stage it was in (no later stage reported), and no result lands."""
    from skelcore.params import Params

    w = window
    w.session.process_from = 0
    sh = shapes.y_shape(3000, seed=5)
    with w.session.batch():
        w.scene.set_cloud(sh.cloud)
        w.scene.set_skeletal(sh.skeletal)
    labels: list[str] = []
    w.session.runner.progressed.connect(lambda f, s: labels.append(s))
    assert w.session.start_evaluation(Params(boundedness_method="paper"))  # the slow estimator
    task = w.session.runner._current
    qtbot.waitUntil(lambda: "skeletal boundedness" in w.stage.toolTip(), timeout=120000)
    pid = task.pid
    assert pid is not None and _alive(pid)
    w.cancel_button.click()
    assert not w.session.runner.running and not w.cancel_button.isVisible()
    assert task.wait(20000)
    assert not _alive(pid)
    n = len(labels)
    qtbot.wait(200)
    assert len(labels) == n and w.scene.evaluation is None
    assert "cancelled" in w.statusBar().currentMessage()


@pytest.mark.window(dialogs="record")
def test_an_input_error_in_the_child_process_is_one_dialog_line(window, qtbot):
    w = window
    w.session.process_from = 0
    sh = shapes.y_shape(300, seed=1)
    cloud = sh.cloud.copy()
    cloud[5, 1] = np.nan
    with w.session.batch():
        w.scene.set_cloud(cloud)
        w.scene.set_skeletal(sh.skeletal)
    with qtbot.waitSignal(w.session.runner.finished, timeout=120000):
        assert w.session.start_evaluation()
    assert w.dialogs == ["cloud: coordinates contain NaN or inf"]
    assert w.scene.evaluation is None and not w.session.runner.running


def test_the_first_frame_of_big_new_data_shows_its_twins_then_full_detail(window, qtbot, monkeypatch):
    """Newly loaded big layers are first drawn through their level-of-detail twins (quick in software
    GL), and the full-detail frame follows by itself; a big drop's evaluation starts after the first."""
    import skelscope.view.scene_view as scene_view

    monkeypatch.setattr(scene_view, "LOD_POINTS", 2000)
    w = window
    view = w.view
    frames: list[tuple[bool, bool]] = []
    view.plotter.ren_win.AddObserver(
        "EndEvent", lambda *a: frames.append((bool(view._actors["cloud"].GetVisibility()),
                                              bool(view._actors["cloud-lod"].GetVisibility()))))
    w.session.process_from = 15_000  # a "big" drop at this size
    w.session.auto_evaluate = True
    started: list[int] = []
    w.session.runner.started.connect(lambda name: started.append(len(frames)))
    sh = shapes.y_shape(10_000, seed=1)
    with w.session.batch():
        w.scene.set_cloud(sh.cloud)
        w.scene.set_skeletal(sh.skeletal)
    assert not started  # not yet: after the first frame
    qtbot.waitUntil(lambda: len(frames) >= 2 and frames[-1] == (True, False), timeout=60000)
    assert frames[0] == (False, True)  # the twins first
    assert started and started[0] >= 1
    w.session.runner.shutdown()
