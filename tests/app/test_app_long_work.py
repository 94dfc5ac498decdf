"""Long work at 1M points: Cancel frees the window at once and the worker stops; quitting while a
task runs cancels it and the process exits 0 without Qt's "Destroyed while thread" abort."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
import threading
import time
from pathlib import Path

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
    qtbot.waitUntil(lambda: w.stage.text() == stages[-1], timeout=5000)  # the label names the running stage
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
    from app.__main__ import _exited
    from app.main_window import MainWindow
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


def test_quitting_while_a_million_point_evaluation_runs_exits_0_without_a_qthread_abort(tmp_path):
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    out = subprocess.run([sys.executable, "-c", _QUIT_SCRIPT, str(tmp_path / "s.ini"), str(MILLION)],
                         capture_output=True, text=True, cwd=ROOT, env=env, timeout=300)
    assert "running at quit: True" in out.stdout, out.stdout + out.stderr
    assert out.returncode == 0, out.stderr
    assert "Destroyed while thread" not in out.stderr and "QThread" not in out.stderr
    assert "Traceback" not in out.stderr


# ---- every stage, the stage label, a bounded quit (issue 10's "Long work") -----------------------

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
    qtbot.waitUntil(lambda: w.stage.text() == target, timeout=60000)  # the label names the stage that runs
    assert task.stage == target and task.isRunning()
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


def test_quitting_waits_for_stuck_tasks_within_one_budget_and_keeps_the_settings(window, tmp_path, monkeypatch):
    """A task inside an engine call without a checkpoint (main window and Study dialog both): closing
    asks for at most SHUTDOWN_WAIT_S of waiting in all, never a second full wait for the Study."""
    from app.study_dialog import StudyDialog
    from app.worker import SHUTDOWN_WAIT_S, Task

    w = window
    release = threading.Event()

    def stuck(progress, cancel):
        progress(0.0, "topology")
        release.wait(60)

    try:
        w.session.runner.start(stuck, "evaluation")
        study = StudyDialog(w, str(tmp_path / "cloud.ply"))
        w._study_dialog = study
        study.show()
        study.runner.start(stuck, "study")
        asked: list[float | None] = []
        real_wait = Task.wait
        monkeypatch.setattr(Task, "wait", lambda self, ms=None: (asked.append(ms), real_wait(self, ms))[1])
        w._add_recent(str(tmp_path / "cloud.ply"))  # not yet written to disk (QSettings syncs later)
        w.close()
        assert asked and None not in asked
        assert sum(asked) <= SHUTDOWN_WAIT_S * 1000 + 1, asked
        assert not study.isVisible() and not w.isVisible()
        assert "cloud.ply" in (tmp_path / "settings.ini").read_text()  # synced: the process may end with os._exit
    finally:
        release.set()
