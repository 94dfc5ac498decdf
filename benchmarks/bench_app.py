"""Viewer benchmarks: launch to first render for 100k / 1M-point clouds (and a 1M
cloud dropped with its 1M skeletal set), frames while the camera moves (level of detail), a pick at 1M
points (the projection alone, and a queued click to the pick panel's text painted), Cancel inside every
stage of a 1M-point evaluation (in a child process, or in a thread with ``--thread``) with the longest
GUI event-loop turn and the File menu's latency meanwhile, Ctrl+Q during it, the longest GUI
event-loop stall during a 4096-point evaluation.

Run under a display, e.g. ``xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python benchmarks/bench_app.py``
(``--only-launch``, ``--only-million --skip-frames --cancel-stages topology,...`` for parts). Each launch
is a fresh process (interpreter, imports in skelscope's order, window, PLY load, first frame).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import numpy as np

ROOT = Path(__file__).resolve().parents[1]

_LAUNCH = r"""
import sys, time
t_start = float(sys.argv[1])
from skelscope.__main__ import import_view_libraries
import_view_libraries()  # as skelscope's main does: the view's libraries first, then Qt
from PySide6 import QtCore, QtWidgets
app = QtWidgets.QApplication(["bench"])
from skelscope.main_window import MainWindow
t_imported = time.time()
w = MainWindow(settings=QtCore.QSettings(sys.argv[3], QtCore.QSettings.Format.IniFormat))
w.show()
app.processEvents()
t_window = time.time()
rendered = []
w.view.plotter.ren_win.AddObserver("EndEvent", lambda *a: rendered.append(time.time()))
t_load = time.time()
if len(sys.argv) > 4:  # the cloud and its skeletal set dropped together (auto-evaluated, as a user's drop)
    assert len(w.session.load_files([sys.argv[2], sys.argv[4]])) == 2, w.errors
else:
    assert w.session.load_as("cloud", sys.argv[2]), w.errors
t_loaded = time.time()
while not [t for t in rendered if t >= t_load] and time.time() < t_loaded + 300:  # the next event-loop turn
    app.processEvents()
t_render = min([t for t in rendered if t >= t_load] or [float("inf")])
cpu_render = time.process_time()  # CPU of the whole process (all threads) up to here: robust under load
img = w.view.image()     # a second frame, read back: the GL work is surely finished (upper bound)
t_image = time.time()
spread = img.max(axis=2).astype(int) - img.min(axis=2)
grey = int(((spread <= 6) & (img[..., 0] > 90) & (img[..., 0] < 235)).sum())
print(f"{t_imported - t_start:.3f} {t_window - t_start:.3f} {t_loaded - t_start:.3f} {t_render - t_start:.3f} {w.scene.cloud.n_points} {grey} {t_image - t_start:.3f} {cpu_render:.3f}")
w.close()
"""


def launch_to_first_render(n: int, tmp: Path, skeletal: bool = False) -> list[float]:
    """A fresh process to the first frame of an n-point cloud (with ``skeletal``: and its n-point
    skeletal set, dropped together, which starts their evaluation as a drop does)."""
    from skelcore import shapes
    from skelcore.io import write_points_ply

    path = tmp / f"cloud_{n}.ply"
    skel_path = tmp / f"skeletal_{n}.ply"
    if not path.exists():
        write_points_ply(path, shapes.sphere_surface(n, seed=0))
    if skeletal and not skel_path.exists():
        write_points_ply(skel_path, shapes.sphere_surface(n, seed=0) * 0.5)
    t0 = time.time()
    out = subprocess.run(
        [sys.executable, "-c", _LAUNCH, repr(t0), str(path), str(tmp / "s.ini"), *([str(skel_path)] if skeletal else [])],
        capture_output=True, text=True, cwd=ROOT, check=True,
    )
    fields = out.stdout.split()
    return [float(x) for x in fields[:4]] + [int(fields[5]), float(fields[6]), float(fields[7])]


def stall_during_evaluation(n: int = 4096) -> tuple[float, float, float]:
    """(longest heartbeat gap while the worker runs, longest including the result landing, eval s)."""
    from PySide6 import QtCore, QtWidgets

    from skelscope.main_window import MainWindow
    from skelcore import shapes

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(["bench"])
    tmp = tempfile.mkdtemp()
    w = MainWindow(settings=QtCore.QSettings(os.path.join(tmp, "s.ini"), QtCore.QSettings.Format.IniFormat))
    w.show()
    app.processEvents()
    sh = shapes.y_shape(n, seed=0)
    from skelcore.curve import CurveSkeleton

    w.session.auto_evaluate = False
    with w.session.batch():
        w.scene.set_cloud(sh.cloud)
        w.scene.set_skeletal(sh.skeletal)
        w.scene.set_curve(CurveSkeleton.from_raw(sh.curve_vertices, sh.curve_edges))
    idle_until = time.perf_counter() + 6.0  # as a user would: the window has been open a few seconds
    while time.perf_counter() < idle_until:
        app.processEvents()
        time.sleep(0.02)
    beats: list[float] = []
    timer = QtCore.QTimer()
    timer.setInterval(10)
    timer.timeout.connect(lambda: beats.append(time.perf_counter()))
    finished_at: list[float] = []
    loop = QtCore.QEventLoop()
    w.session.runner.finished.connect(lambda _n: (finished_at.append(time.perf_counter()), QtCore.QTimer.singleShot(500, loop.quit)))
    timer.start()
    t0 = time.perf_counter()
    w.session.start_evaluation()
    loop.exec()
    timer.stop()
    beats = [t0] + beats
    gaps = [(b - a, b) for a, b in zip(beats, beats[1:])]
    during = max(g for g, t in gaps if t <= finished_at[0]) if gaps else float("nan")
    overall = max(g for g, _ in gaps)
    elapsed = w.scene.evaluation.timings["total"]
    w.close()
    return during, overall, elapsed


def cancel_latency() -> float:
    """Seconds from Cancel to the worker having stopped, on a slow ('paper' estimator) 4096 run."""
    from PySide6 import QtCore, QtWidgets

    from skelscope.main_window import MainWindow
    from skelcore import shapes
    from skelcore.params import Params

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(["bench"])
    tmp = tempfile.mkdtemp()
    w = MainWindow(settings=QtCore.QSettings(os.path.join(tmp, "s.ini"), QtCore.QSettings.Format.IniFormat))
    w.session.auto_evaluate = False
    sh = shapes.y_shape(4096, seed=0)
    w.scene.set_cloud(sh.cloud)
    w.scene.set_skeletal(sh.skeletal)
    w.session.start_evaluation(Params(boundedness_method="paper"))
    task = w.session.runner._current
    end = time.perf_counter() + 1.5
    while time.perf_counter() < end:
        app.processEvents()
        time.sleep(0.01)
    t0 = time.perf_counter()
    w.session.cancel()
    task.wait()
    latency = time.perf_counter() - t0
    app.processEvents()
    assert w.scene.evaluation is None
    w.close()
    return latency


def _million_window(n: int = 1_000_000, skeletal: bool = True):
    from PySide6 import QtCore, QtWidgets

    from skelscope.main_window import MainWindow
    from skelcore import shapes

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(["bench"])
    tmp = tempfile.mkdtemp()
    w = MainWindow(settings=QtCore.QSettings(os.path.join(tmp, "s.ini"), QtCore.QSettings.Format.IniFormat))
    w.session.auto_evaluate = False
    w.resize(1500, 950)
    w.show()
    app.processEvents()
    cloud = shapes.sphere_surface(n, seed=0)
    with w.session.batch():
        w.scene.set_cloud(cloud)
        if skeletal:
            w.scene.set_skeletal(cloud * 0.5)
    w.view.image()
    return app, w, cloud


def frames_while_moving(n: int = 1_000_000, frames: int = 8) -> dict[str, float]:
    """Median frame time (render + GL finish) of a 1M-point cloud and its 1M-point skeletal set, at
    rest (full detail) and while the camera moves (level-of-detail twins), rotating 5 degrees a frame."""
    app, w, _ = _million_window(n)
    ren_win = w.view.plotter.ren_win
    camera = w.view.plotter.renderer.GetActiveCamera()

    def timed(moving: bool) -> float:
        w.view._set_moving(moving)
        times = []
        for _ in range(frames):
            camera.Azimuth(5.0)
            t0 = time.perf_counter()
            ren_win.Render()
            w.view.plotter.GetRenderWindow().WaitForCompletion()
            times.append(time.perf_counter() - t0)
        return sorted(times)[len(times) // 2]

    out = {"rest": timed(False), "moving": timed(True)}
    w.view._set_moving(False)
    w.close()
    app.processEvents()
    return out


def pick_time(n: int = 1_000_000, picks: int = 5) -> float:
    """Median seconds of a pick among a 1M-point skeletal set (numpy projection, marker queued)."""
    app, w, cloud = _million_window(n)
    w.scene.set_visible("cloud", False)
    w.view.image()
    sk = w.scene.skeletal.points
    times = []
    for i in range(picks):
        x, y = w.view.world_to_display(sk[int(np.argmax(sk[:, 2])) - i])
        t0 = time.perf_counter()
        info = w.view.pick_display(x, y)
        times.append(time.perf_counter() - t0)
        assert info is not None
    w.close()
    app.processEvents()
    return sorted(times)[len(times) // 2]


CANCEL_STAGES = ("skeletal boundedness", "topology", "skeletal centeredness", "skeletal smoothness")
"""The stages of the 1M-point evaluation (cloud + skeletal set in pointwise correspondence). Coverage is
not computed above ``coverage_max_points`` (200k), so it has no stage at 1M."""


def _stand_in_boundedness(cloud: np.ndarray, queries: np.ndarray, *, params: object = None,
                          checkpoint: Any = lambda f: None) -> np.ndarray:
    """1 for every query, after its checkpoints (as benchmarks/bench_stages.py does): the stages after
    boundedness come without waiting for 1M boundedness queries (thread mode only: a child process
    imports the real engine)."""
    checkpoint(0.0)
    checkpoint(1.0)
    return np.ones(len(queries))


PUMP_CPU: list[float] = []  # the GUI thread's CPU time in the longest turn of the last _pump


def _pump(app: Any, seconds: float, until: Any = lambda: False) -> float:
    """Run the event loop for ``seconds`` (or until ``until()``); returns the longest event-loop turn
    seen beyond the 10 ms sleeps (a worker holding the GIL, or the GUI's own work, shows up here).
    ``PUMP_CPU[0]`` is the GUI thread's CPU time during that turn: far below the turn's wall time,
    the thread was waiting (for the GIL, or for a core on a loaded machine), not working."""
    end = time.perf_counter() + seconds
    last = time.perf_counter()
    last_cpu = time.thread_time()
    longest, cpu_of_longest = 0.0, 0.0
    while time.perf_counter() < end and not until():
        app.processEvents()
        time.sleep(0.01)
        now, cpu = time.perf_counter(), time.thread_time()
        if now - last - 0.01 > longest:
            longest, cpu_of_longest = now - last - 0.01, cpu - last_cpu
        last, last_cpu = now, cpu
    PUMP_CPU[:] = [cpu_of_longest]
    return longest


def menu_latency(app: Any, w: Any, timeout: float = 30.0) -> float:
    """Seconds from a (queued) click on the File menu to the menu painted on screen, then closed."""
    from PySide6 import QtCore, QtGui

    bar = w.menuBar()
    menu = bar.actions()[0].menu()
    painted: list[float] = []

    class Watch(QtCore.QObject):
        def eventFilter(self, obj: Any, event: Any) -> bool:  # noqa: N802
            if event.type() == QtCore.QEvent.Type.Paint and not painted:
                painted.append(time.perf_counter())
            return False

    watch = Watch()
    menu.installEventFilter(watch)
    pos = QtCore.QPointF(bar.actionGeometry(bar.actions()[0]).center())
    glob = QtCore.QPointF(bar.mapToGlobal(pos.toPoint()))
    t0 = time.perf_counter()
    for kind in (QtCore.QEvent.Type.MouseButtonPress, QtCore.QEvent.Type.MouseButtonRelease):
        app.postEvent(bar, QtGui.QMouseEvent(kind, pos, glob, QtCore.Qt.MouseButton.LeftButton,
                                             QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier))
    end = t0 + timeout
    while not painted and time.perf_counter() < end:
        app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.AllEvents, 5)
    menu.removeEventFilter(watch)
    menu.hide()
    app.processEvents()
    return (painted[0] - t0) if painted else float("inf")


def cancel_in_every_stage(stages: tuple[str, ...] = CANCEL_STAGES, into: float = 2.0, wait: float = 1800.0,
                          stop_wait: float = 600.0, thread: bool = False) -> list[tuple]:
    """Cancel a 1M-point evaluation inside each stage: start it, wait (at most ``wait`` s) until the
    label names the stage (it names every stage running side by side), let it run ``into`` s more
    (less if the stage ends first) while the File menu is opened by a queued click, press Cancel.

    ``thread``: the evaluation in a thread instead of a child process (stages after boundedness then reached
    with :func:`_stand_in_boundedness`); else in a child process, as the window runs 1M points.
    Returns, per stage: (stage aimed at, label shown at Cancel, s until the stage began, s into it,
    s until the window was idle, s until the worker stopped (None: not within ``stop_wait`` s),
    longest event-loop turn while the stage ran, the GUI thread's CPU s in it, s from a click on File
    to its menu painted, stand-in used)."""
    import importlib

    ev_mods = [importlib.import_module(f"skelcore.stages.{m}") for m in ("catalogue", "assemble")]
    real_boundedness = ev_mods[0].boundedness
    app, w, _ = _million_window(1_000_000)
    w.session.process_from = 10**12 if thread else 0
    out = []
    for target in stages:
        stand_in = thread and target in CANCEL_STAGES[CANCEL_STAGES.index("skeletal boundedness") + 1:]
        for ev_mod in ev_mods:
            ev_mod.boundedness = _stand_in_boundedness if stand_in else real_boundedness
        assert w.session.start_evaluation()
        task = w.session.runner._current
        t_start = time.perf_counter()
        running = lambda: target in task.stage.split(" + ")  # noqa: E731
        _pump(app, wait, lambda: running() or task.isFinished())
        reached = time.perf_counter() - t_start
        t_in = time.perf_counter()
        gap = _pump(app, into / 2, lambda: not running())
        gap_cpu = PUMP_CPU[0]
        menu = menu_latency(app, w) if running() else float("nan")
        gap2 = _pump(app, into / 2, lambda: not running())
        if gap2 > gap:
            gap, gap_cpu = gap2, PUMP_CPU[0]
        label = w.stage.toolTip()
        t0 = time.perf_counter()
        w.cancel_button.click()
        idle = time.perf_counter() - t0
        assert not w.session.runner.running
        stopped = time.perf_counter() - t0 if task.wait(stop_wait * 1000) else None
        out.append((target, label, reached, t0 - t_in, idle, stopped, gap, gap_cpu, menu, stand_in))
        _pump(app, 0.5)
    for ev_mod in ev_mods:
        ev_mod.boundedness = real_boundedness
    w.close()
    return out


def pick_click_to_text(n: int = 1_000_000, picks: int = 3) -> list[float]:
    """Seconds from a (queued) left click on a skeletal point to the pick panel's text painted, among
    1M skeletal points with their evaluation shown (the support is then computed in the background)."""
    from PySide6 import QtCore, QtGui

    app, w, cloud = _million_window(n)
    with __import__("contextlib").suppress(Exception):
        w.session.process_from = 0
    done: list[Any] = []
    w.session.evaluated.connect(done.append)
    w.session.start_evaluation()
    _pump(app, 3600, lambda: bool(done))
    _pump(app, 3.0)
    w.scene.set_visible("cloud", False)
    w.view.image()
    sk = w.scene.skeletal.points
    widget = w.view.plotter
    ratio = widget.devicePixelRatioF()
    viewport = w.pick.text.viewport()
    out = []
    for i in range(picks):
        x, y = w.view.world_to_display(sk[int(np.argmax(sk[:, 2])) - 7 * i])
        pos = QtCore.QPointF(x / ratio, widget.height() - y / ratio)
        painted: list[float] = []

        class Watch(QtCore.QObject):
            def eventFilter(self, obj: Any, event: Any) -> bool:  # noqa: N802
                if event.type() == QtCore.QEvent.Type.Paint and w.pick.info is not None and not painted:
                    painted.append(time.perf_counter())
                return False

        w.pick.show_info(None)
        app.processEvents()
        watch = Watch()
        viewport.installEventFilter(watch)
        glob = QtCore.QPointF(widget.mapToGlobal(pos.toPoint()))
        t0 = time.perf_counter()
        for kind in (QtCore.QEvent.Type.MouseButtonPress, QtCore.QEvent.Type.MouseButtonRelease):
            app.postEvent(widget, QtGui.QMouseEvent(kind, pos, glob, QtCore.Qt.MouseButton.LeftButton,
                                                    QtCore.Qt.MouseButton.LeftButton,
                                                    QtCore.Qt.KeyboardModifier.NoModifier))
        end = t0 + 60
        while not painted and time.perf_counter() < end:
            app.processEvents(QtCore.QEventLoop.ProcessEventsFlag.AllEvents, 5)
        viewport.removeEventFilter(watch)
        out.append((painted[0] - t0) if painted else float("inf"))
        _pump(app, 2.0, lambda: not w.supports.busy)
    w.close()
    app.processEvents()
    return out


_QUIT = r"""
import sys, time
from skelscope.__main__ import import_view_libraries
import_view_libraries()
from PySide6 import QtCore, QtWidgets
app = QtWidgets.QApplication(["bench-quit"])
from skelscope.__main__ import _exited
from skelscope.main_window import MainWindow
from skelcore import shapes
w = MainWindow(settings=QtCore.QSettings(sys.argv[1], QtCore.QSettings.Format.IniFormat))
w.session.auto_evaluate = False
if sys.argv[4] == "thread":
    w.session.process_from = 10**12
cloud = shapes.sphere_surface(1_000_000, seed=0)
with w.session.batch():
    w.scene.set_cloud(cloud)
    w.scene.set_skeletal(cloud * 0.05)
w.show()
def quit_now():
    print(f"{time.time():.4f} {w.session.runner.stage}", flush=True)
    w.actions_by_name["quit"].trigger()
armed = []
def arm(_fraction, stage):  # the delay counts from the first report of the stage aimed at (any: sys.argv[3] "")
    if not armed and sys.argv[3] in stage.split(" + ") + [""]:
        armed.append(stage)
        QtCore.QTimer.singleShot(int(float(sys.argv[2]) * 1000), quit_now)
w.session.runner.progressed.connect(arm)
QtCore.QTimer.singleShot(100, w.session.start_evaluation)
sys.exit(_exited(app.exec()))
"""


def quit_while_running(delay: float, tmp: Path, stage: str = "", thread: bool = False) -> tuple[float, int, bool, str]:
    """(s from Ctrl+Q to the process's end, exit status, Qt's thread abort seen, stage) for a quit
    ``delay`` s after a 1M-point evaluation first reported ``stage`` (any stage when "")."""
    proc = subprocess.run([sys.executable, "-c", _QUIT, str(tmp / "q.ini"), str(delay), stage,
                           "thread" if thread else "process"], capture_output=True, text=True, cwd=ROOT)
    ended = time.time()
    quit_at, _, stage = proc.stdout.strip().partition(" ")
    return ended - float(quit_at), proc.returncode, "Destroyed while thread" in proc.stderr, stage


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip-launch", action="store_true", help="skip the launch-to-first-render runs")
    parser.add_argument("--only-launch", action="store_true", help="only the launch-to-first-render runs")
    parser.add_argument("--launch-runs", type=int, default=2, help="fresh launches per cloud size (best reported)")
    parser.add_argument("--skip-cancel", action="store_true", help="skip the Cancel latency run")
    parser.add_argument("--skip-million", action="store_true", help="skip the 1M-point frames, pick, cancel and quit")
    parser.add_argument("--only-million", action="store_true", help="only the 1M-point frames, pick, cancel and quit")
    parser.add_argument("--million-part", choices=("frames", "pick", "click", "cancel"), help=argparse.SUPPRESS)
    parser.add_argument("--cancel-stages", default=",".join(CANCEL_STAGES),
                        help="comma-separated stages to cancel in at 1M (default: all)")
    parser.add_argument("--thread", action="store_true",
                        help="evaluate 1M points in a thread (default: a child process)")
    parser.add_argument("--skip-click", action="store_true", help="skip the click-to-text pick (evaluates 1M points)")
    parser.add_argument("--stop-wait", type=float, default=600.0, help="s to wait for the worker after a Cancel")
    parser.add_argument("--skip-frames", action="store_true", help="skip the 1M-point frames and pick")
    parser.add_argument("--stall-runs", type=int, default=1,
                        help="evaluations timed for the GUI stall, each in a fresh process (best reported)")
    parser.add_argument("--stall-once", action="store_true", help=argparse.SUPPRESS)  # one run, in this process
    args = parser.parse_args(argv)
    if args.million_part:  # one part, in this process (a fresh one per part: no warm caches)
        sys.path.insert(0, str(ROOT))
        stages = tuple(x.strip() for x in args.cancel_stages.split(",") if x.strip())
        part = {"frames": frames_while_moving, "pick": pick_time, "click": pick_click_to_text,
                "cancel": lambda: cancel_in_every_stage(stages, stop_wait=args.stop_wait, thread=args.thread)
                }[args.million_part]
        print(repr(part()))
        return 0
    if args.stall_once:
        sys.path.insert(0, str(ROOT))
        print(*stall_during_evaluation(4096))
        return 0
    sys.path.insert(0, str(ROOT))
    tmp = Path(tempfile.mkdtemp(prefix="bench-app-"))
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at start")
    if not args.skip_million and not args.only_launch:
        run = lambda part: eval(subprocess.run([sys.executable, __file__, "--million-part", part,  # noqa: E731,S307
                                                "--cancel-stages", args.cancel_stages, "--stop-wait", str(args.stop_wait),
                                                *(["--thread"] if args.thread else [])],
                                               capture_output=True, text=True, cwd=ROOT, check=True).stdout.strip()
                                .splitlines()[-1], {"nan": float("nan"), "inf": float("inf")})
        if not args.skip_frames:
            frames = run("frames")
            print(f"\n1M-point cloud + 1M-point skeletal set, median frame while rotating: {frames['rest'] * 1000:.0f} "
                  f"ms at full detail, {frames['moving'] * 1000:.0f} ms with the level-of-detail twins (camera moving)"
                  f"  [load {os.getloadavg()[0]:.1f}]")
            print(f"pick among 1M skeletal points: {run('pick') * 1000:.0f} ms (median of 5)  "
                  f"[load {os.getloadavg()[0]:.1f}]")
        if not args.skip_click:
            clicks = run("click")
            print(f"click on one of 1M evaluated skeletal points to its text painted: "
                  f"{', '.join(f'{c * 1000:.0f}' for c in clicks)} ms  [load {os.getloadavg()[0]:.1f}]")
        mode = "a thread" if args.thread else "a child process"
        print(f"\nCancel inside each stage of a 1M-point evaluation (1M cloud + 1M skeletal set) in {mode}:\n")
        print("| stage aimed at | label shown (stages running) | stage began after | Cancel after | window idle after "
              "| worker stopped after | longest GUI event-loop turn (GUI thread's CPU in it) "
              "| File menu painted after the click | load |")
        print("|---|---|---|---|---|---|---|---|---|")
        for target, label, reached, into, idle, stopped, gap, gap_cpu, menu, stand_in in run("cancel"):
            print(f"| {target}{' (boundedness stand-in)' if stand_in else ''} | {label} | {reached:.1f} s "
                  f"| {into:.2f} s into it | {idle * 1000:.0f} ms | "
                  f"{f'> {args.stop_wait:g} s' if stopped is None else f'{stopped:.2f} s'} | {gap * 1000:.0f} ms "
                  f"({gap_cpu * 1000:.0f} ms) | {menu * 1000:.0f} ms | {os.getloadavg()[0]:.1f} |")
        for delay, stage in ((0.5, ""), (3.0, ""), (2.0, "skeletal boundedness"), (2.0, "topology"),
                             (2.0, "skeletal centeredness")):
            took, code, aborted, at = quit_while_running(delay, tmp, stage, args.thread)
            print(f"Ctrl+Q {delay:g} s into {'a 1M-point evaluation' if not stage else repr(stage)} (stage '{at}'): "
                  f"process ended {took:.2f} s later, exit status {code}, QThread abort: {'yes' if aborted else 'no'}"
                  f"  [load {os.getloadavg()[0]:.1f}]")
    if args.only_million:
        return 0
    if not args.skip_launch:
        print("\n| cloud | imports done | window shown | file loaded | first frame rendered (launch to first render) "
              "| + a second frame read back | CPU s to the first frame | cloud-grey pixels in the frame | load |")
        print("|---|---|---|---|---|---|---|---|---|")
        for n, skeletal in ((100_000, False), (1_000_000, False), (1_000_000, True)):
            runs = [launch_to_first_render(n, tmp, skeletal) for _ in range(max(args.launch_runs, 1))]
            best = min(runs, key=lambda r: r[3])
            cpu = min(r[6] for r in runs)
            every = ", ".join(f"{r[3]:.2f}" for r in runs)
            print(f"| {n:,} points{' + skeletal set' if skeletal else ''} | {best[0]:.2f} s | {best[1]:.2f} s | "
                  f"{best[2]:.2f} s | **{best[3]:.2f} s** (runs: {every}) | {best[5]:.2f} s "
                  f"| {cpu:.2f} | {best[4]} | {os.getloadavg()[0]:.1f} |")
        if args.only_launch:
            return 0
    stalls = []
    for _ in range(max(args.stall_runs, 1)):  # a fresh process each: no warm caches from a previous run
        out = subprocess.run([sys.executable, __file__, "--stall-once"], capture_output=True, text=True, cwd=ROOT,
                             check=True)
        stalls.append(tuple(float(x) for x in out.stdout.split()[-3:]))
    during, overall, elapsed = min(stalls, key=lambda r: r[1])
    runs = ", ".join(f"{o * 1000:.0f}" for _, o, _ in stalls)
    print(f"\nGUI stall, 4096-point evaluation (skeletal + curve, {elapsed:.2f} s): longest heartbeat gap "
          f"{during * 1000:.0f} ms while the worker ran, {overall * 1000:.0f} ms including drawing the result"
          + (f" (best of {len(stalls)}; every run including the result: {runs} ms)" if len(stalls) > 1 else ""))
    if not args.skip_cancel:
        print(f"Cancel latency ('paper' estimator, 4096 points): {cancel_latency() * 1000:.0f} ms")
    print(f"load average {os.getloadavg()[0]:.1f} at the end")
    return 0


if __name__ == "__main__":
    sys.exit(main())
