"""Long work at 1M points: Cancel frees the window at once and the worker stops; quitting while a
task runs cancels it and the process exits 0 without Qt's "Destroyed while thread" abort."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest
from PySide6 import QtCore, QtWidgets

from skelcore import shapes

pytestmark = pytest.mark.gui

ROOT = Path(__file__).resolve().parents[1]
MILLION = 1_000_000


@pytest.fixture(scope="module")
def million():
    cloud = shapes.sphere_surface(MILLION, seed=0)
    return cloud, cloud * 0.05  # a skeletal set in pointwise correspondence (the cloud contracted)


def test_cancel_during_a_million_point_evaluation_stops_the_worker_and_the_window_survives(qtbot, tmp_path, million,
                                                                                          monkeypatch):
    from app.main_window import MainWindow

    monkeypatch.setattr(QtWidgets.QMessageBox, "critical", lambda *a, **k: pytest.fail(f"error dialog {a[2]!r}"))
    w = MainWindow(settings=QtCore.QSettings(str(tmp_path / "s.ini"), QtCore.QSettings.Format.IniFormat))
    qtbot.addWidget(w)
    w.session.auto_evaluate = False
    w.show()
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
