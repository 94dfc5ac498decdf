"""Closing the viewer after real work (docs/performance.md section 5, docs/guide/viewer.md).

Each round is a fresh ``skelscope`` process, as a user's: the window shown, a sphere of ``n`` points
dropped with a skeletal set of as many (the same inputs as bench_app.py's start-up), evaluated (in a
child process from 200k points), coloured by boundedness and one skeletal point picked, whose support
(the direction map over the whole cloud) runs in its own thread; then Ctrl+Q is pressed on the window,
timed from the key to the process's end (the parent sees the exit). ``support``: ``done``, the pick's
support shown before the key; ``computing``, the key pressed 0.3 s into it; ``evaluating``, no pick,
the key pressed 2 s into the evaluation of the cloud with half its skeletal set (150k points: in a
thread of the window's process, which closing once waited for, up to ``SHUTDOWN_WAIT_S``, 1.5 s).
extra_info splits each close: ``key_s`` (the line sent to the key pressed), ``window_close_s`` (the
key to the event loop's end: closeEvent, the view's close; ``window_close_cpu_s``, that thread's CPU
seconds meanwhile, which the load does not inflate), ``exit_s`` (to the exit the parent sees); and
the evaluation's seconds (untimed).
Needs a display (pytest-xvfb); the 1M cases are ``large``.
"""

from __future__ import annotations

import subprocess
import sys
import time

import pytest

from bench_app import ROOT, _write_inputs, display  # noqa: F401 - the display fixture

#: argv: the cloud's PLY, the skeletal set's PLY, a settings file, "done", "computing" or "evaluating".
#: Prints "ready" and the evaluation's seconds once the pick is made, waits for a line on stdin, presses
#: Ctrl+Q, prints the key's and the event loop's end's time.time() and how Ctrl+Q was given (the key, or
#: its action where no window manager made the window active), then exits as skelscope does.
_CLOSE = r"""
import select, sys, time
from skelscope.__main__ import _exited, import_view_libraries
import_view_libraries()
from PySide6 import QtCore, QtWidgets
from PySide6.QtTest import QTest
app = QtWidgets.QApplication(["bench"])
from skelscope.main_window import MainWindow
w = MainWindow(settings=QtCore.QSettings(sys.argv[3], QtCore.QSettings.Format.IniFormat))
w.resize(1100, 750)
w.show()
app.processEvents()

def idle(done, limit=900.0):
    end = time.time() + limit
    while not done():
        if time.time() > end:
            raise SystemExit("timed out")
        app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.AllEvents, 20)

t0 = time.time()
with w.session.batch():
    assert w.session.load_as("cloud", sys.argv[1])
    assert w.session.load_as("skeletal", sys.argv[2])
if sys.argv[4] == "evaluating":  # in a thread of this process (under 200k points): Ctrl+Q 2 s into it
    idle(lambda: w.session.runner.running)
    started = time.time()
    idle(lambda: time.time() > started + 2.0)
    assert w.session.runner.running, "the evaluation ended before the key"
else:
    idle(lambda: w.scene.evaluation is not None and not w.session.runner.running)
evaluated = time.time() - t0
if sys.argv[4] == "evaluating":
    pass
elif sys.argv[4] == "done":
    w.scene.set_metric("boundedness")
    idle(lambda: not w.view.render_pending)
    w.select_element("skeletal", "points", 0)
    idle(lambda: not w.supports.busy)
else:
    w.scene.set_metric("boundedness")
    idle(lambda: not w.view.render_pending)
    w.select_element("skeletal", "points", 0)
    picked = time.time()
    idle(lambda: time.time() > picked + 0.3)
    assert w.supports.busy, "the support ended before the key"
w.activateWindow()
idle(lambda: QtWidgets.QApplication.activeWindow() is w or time.time() > t0 + evaluated + 2)
print(f"ready {evaluated:.3f}", flush=True)
idle(lambda: select.select([sys.stdin], [], [], 0)[0])
sys.stdin.readline()
pressed, via, cpu = [], [], []

def press():  # the key, when the window is active (no window manager may make it so), else its action
    pressed.append(time.time())
    cpu.append(time.thread_time())
    if QtWidgets.QApplication.activeWindow() is w:
        QTest.keyClick(w, QtCore.Qt.Key.Key_Q, QtCore.Qt.KeyboardModifier.ControlModifier)
    if w.isVisible():
        via.append("action")
        w.actions_by_name["quit"].trigger()

QtCore.QTimer.singleShot(0, press)
code = app.exec()
print(f"{pressed[0]!r} {time.time()!r} {via[0] if via else 'key'} {time.thread_time() - cpu[0]!r}", flush=True)
_exited(code)
"""


@pytest.mark.parametrize("n,support", [
    pytest.param(100_000, "done", id="100000-support-done"),
    pytest.param(100_000, "evaluating", id="100000-evaluating"),
    pytest.param(1_000_000, "done", marks=pytest.mark.large, id="1000000-support-done"),
    pytest.param(1_000_000, "computing", marks=pytest.mark.large, id="1000000-support-computing"),
])
def test_viewer_close_after_work(measure, benchmark, display, tmp_path, n, support):  # noqa: F811
    """Ctrl+Q to the process's end (timed: from the line that makes the window press the key to the
    exit the parent sees), each round a fresh process that evaluated and picked first (untimed)."""
    cloud, skeletal = _write_inputs(tmp_path, n)
    if support == "evaluating":  # half the skeletal set: 150k points in all, evaluated in a thread
        from skelcore.io import load_points, write_points_ply

        half = tmp_path / f"skeletal_{n // 2}.ply"
        write_points_ply(half, load_points(str(skeletal))[: n // 2])
        skeletal = half
    key_s: list[float] = []  # the line sent to the key pressed (the child's event loop's turn)
    window_s: list[float] = []  # the key to the event loop's end (closeEvent, the view's close)
    exit_s: list[float] = []  # the event loop's end to the exit seen (os._exit, the kernel's teardown)
    evaluated_s: list[float] = []
    window_cpu_s: list[float] = []  # the window's thread's CPU seconds from the key to the event loop's end
    given: list[str] = []  # "key" (Ctrl+Q typed on the active window) or "action" (its action triggered)

    def launch():
        proc = subprocess.Popen([sys.executable, "-c", _CLOSE, str(cloud), str(skeletal), str(tmp_path / "s.ini"),
                                 support], stdin=subprocess.PIPE, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                text=True, cwd=ROOT)
        ready = proc.stdout.readline().split()
        if ready[:1] != ["ready"]:
            proc.kill()
            pytest.fail(f"the window did not get ready: {proc.stderr.read()[-2000:]}")
        evaluated_s.append(float(ready[1]))
        return (proc,), {}

    def close(proc):
        sent = time.time()
        proc.stdin.write("go\n")
        proc.stdin.flush()
        proc.wait(timeout=60)
        ended = time.time()
        line = proc.stdout.readline()
        assert proc.returncode == 0 and line, proc.stderr.read()[-2000:]
        pressed, loop_end, how, cpu = line.split()
        pressed, loop_end = float(pressed), float(loop_end)
        given.append(how)
        window_cpu_s.append(float(cpu))
        key_s.append(pressed - sent)
        window_s.append(loop_end - pressed)
        exit_s.append(ended - loop_end)

    measure(close, rounds=3, warmup=0, setup=launch)
    benchmark.extra_info.update(n_points=n, skeletal_points=n // 2 if support == "evaluating" else n, support=support,
                                display=display,
                                key_s=[round(s, 3) for s in key_s], window_close_s=[round(s, 3) for s in window_s],
                                window_close_cpu_s=[round(s, 3) for s in window_cpu_s],
                                exit_s=[round(s, 3) for s in exit_s], ctrl_q=given,
                                evaluation_s=[round(s, 3) for s in evaluated_s])
