"""Viewer benchmarks (issue 3): launch to first render for 100k / 1M-point clouds, the longest GUI
event-loop stall during a 4096-point evaluation (QTimer heartbeat), and how fast Cancel stops a run.

Run under a display, e.g. ``xvfb-run -a -s "-screen 0 1600x1000x24" .venv/bin/python benchmarks/bench_app.py``.
Each launch measurement is a fresh process (interpreter start, imports, window, PLY load, first frame).
"""

from __future__ import annotations

import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]

_LAUNCH = r"""
import sys, time
t_start = float(sys.argv[1])
from PySide6 import QtCore, QtWidgets
app = QtWidgets.QApplication(["bench"])
from app.main_window import MainWindow
t_imported = time.time()
w = MainWindow(settings=QtCore.QSettings(sys.argv[3], QtCore.QSettings.Format.IniFormat))
w.show()
app.processEvents()
t_window = time.time()
rendered = []
w.view.plotter.ren_win.AddObserver("EndEvent", lambda *a: rendered.append(time.time()))
assert w.session.load_as("cloud", sys.argv[2]), w.errors
t_loaded = time.time()
while not [t for t in rendered if t >= t_loaded]:  # the view repaints on the next event-loop turn
    app.processEvents()
t_render = min(t for t in rendered if t >= t_loaded)
img = w.view.image()     # a second frame, read back: the GL work is surely finished (upper bound)
t_image = time.time()
spread = img.max(axis=2).astype(int) - img.min(axis=2)
grey = int(((spread <= 6) & (img[..., 0] > 90) & (img[..., 0] < 235)).sum())
print(f"{t_imported - t_start:.3f} {t_window - t_start:.3f} {t_loaded - t_start:.3f} {t_render - t_start:.3f} {w.scene.cloud.n_points} {grey} {t_image - t_start:.3f}")
w.close()
"""


def launch_to_first_render(n: int, tmp: Path) -> list[float]:
    from skelcore import shapes
    from skelcore.io import write_points_ply

    path = tmp / f"cloud_{n}.ply"
    if not path.exists():
        write_points_ply(path, shapes.sphere_surface(n, seed=0))
    t0 = time.time()
    out = subprocess.run(
        [sys.executable, "-c", _LAUNCH, repr(t0), str(path), str(tmp / "s.ini")],
        capture_output=True, text=True, cwd=ROOT, check=True,
    )
    fields = out.stdout.split()
    return [float(x) for x in fields[:4]] + [int(fields[5]), float(fields[6])]


def stall_during_evaluation(n: int = 4096) -> tuple[float, float, float]:
    """(longest heartbeat gap while the worker runs, longest including the result landing, eval s)."""
    from PySide6 import QtCore, QtWidgets

    from app.main_window import MainWindow
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

    from app.main_window import MainWindow
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


def main(argv: list[str] | None = None) -> int:
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--skip-launch", action="store_true", help="skip the launch-to-first-render runs")
    parser.add_argument("--skip-cancel", action="store_true", help="skip the Cancel latency run")
    parser.add_argument("--stall-runs", type=int, default=1,
                        help="evaluations timed for the GUI stall, each in a fresh process (best reported)")
    parser.add_argument("--stall-once", action="store_true", help=argparse.SUPPRESS)  # one run, in this process
    args = parser.parse_args(argv)
    if args.stall_once:
        sys.path.insert(0, str(ROOT))
        print(*stall_during_evaluation(4096))
        return 0
    sys.path.insert(0, str(ROOT))
    tmp = Path(tempfile.mkdtemp(prefix="bench-app-"))
    print(f"machine: {os.cpu_count()} cores, load average {os.getloadavg()[0]:.1f} at start")
    if not args.skip_launch:
        print("\n| cloud | imports done | window shown | file loaded | first frame rendered (launch to first render) | + a second frame read back | cloud-grey pixels in the frame |")
        print("|---|---|---|---|---|---|---|")
        for n in (100_000, 1_000_000):
            runs = [launch_to_first_render(n, tmp) for _ in range(2)]
            best = min(runs, key=lambda r: r[3])
            print(f"| {n:,} points | {best[0]:.2f} s | {best[1]:.2f} s | {best[2]:.2f} s | **{best[3]:.2f} s** | {best[5]:.2f} s | {best[4]} |")
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
