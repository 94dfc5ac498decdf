"""The viewer's start-up (docs/guide/viewer.md): a fresh process launched, skelscope's imports in its
order (the view's libraries, then Qt), the main window shown, a PLY cloud of 100k points (1M with
``--bench-large``) loaded, until its first frame is rendered; the process then exits at once. Its
own phases (imports, window, loaded, first frame; seconds from the launch) are in the case's
extra_info. Needs a display: pytest-xvfb starts Xvfb for the run when it is installed (software
OpenGL); without DISPLAY the cases are skipped."""

from __future__ import annotations

import os
import subprocess
import sys
import time
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[1]

#: argv: launch time, the cloud's PLY, a settings file. Prints the phases' seconds from the launch.
_LAUNCH = r"""
import os, sys, time
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
assert w.session.load_as("cloud", sys.argv[2]), w.errors
t_loaded = time.time()
while not [t for t in rendered if t >= t_load] and time.time() < t_loaded + 300:  # the next event-loop turn
    app.processEvents()
t_render = min([t for t in rendered if t >= t_load] or [float("inf")])
print(f"{t_imported - t_start:.3f} {t_window - t_start:.3f} {t_loaded - t_start:.3f} {t_render - t_start:.3f} "
      f"{w.scene.cloud.n_points}", flush=True)
os._exit(0)
"""


@pytest.fixture(scope="module")
def display() -> str:
    if not os.environ.get("DISPLAY"):
        pytest.skip("no DISPLAY (pytest-xvfb starts Xvfb when it is installed)")
    pytest.importorskip("PySide6")
    pytest.importorskip("pyvistaqt")
    return os.environ["DISPLAY"]


@pytest.mark.parametrize("n", [100_000, pytest.param(1_000_000, marks=pytest.mark.large)])
def test_viewer_start_up(measure, benchmark, display, tmp_path, n):
    from skelcore import shapes
    from skelcore.io import write_points_ply

    path = tmp_path / f"cloud_{n}.ply"
    write_points_ply(path, shapes.sphere_surface(n, seed=0))
    phases: list[list[str]] = []

    def launch():
        out = subprocess.run([sys.executable, "-c", _LAUNCH, repr(time.time()), str(path), str(tmp_path / "s.ini")],
                             capture_output=True, text=True, cwd=ROOT, timeout=600)
        assert out.returncode == 0, out.stderr[-2000:]
        phases.append(out.stdout.split())

    measure(launch, rounds=3)
    imported, window, loaded, render, points = phases[-1]
    assert int(points) == n and render != "inf"
    benchmark.extra_info.update(n_points=n, display=display, imported_s=float(imported), window_s=float(window),
                                loaded_s=float(loaded), first_frame_s=float(render))


@pytest.mark.parametrize("n", [100_000, pytest.param(1_000_000, marks=pytest.mark.large)])
def test_viewer_stale_support_stops(measure, benchmark, n):
    """A pick's support still computing when a newer pick replaces it (the boundedness direction map of
    a point inside a sphere of ``n`` points, seconds on a million): from the cancel to the end of its
    thread, which until then shares the cores and the interpreter with the new pick's support."""
    pytest.importorskip("PySide6")
    from skelcore import shapes
    from skelcore.metrics.supports import direction_map
    from skelcore.params import Params
    from skelscope.support_controller import _Job

    cloud = shapes.sphere_surface(n, seed=0)
    centre = cloud.mean(axis=0)
    params = Params()
    delivered: list[object] = []
    t0 = time.perf_counter()
    direction_map(cloud, centre, params=params)
    whole = time.perf_counter() - t0

    def start():
        job = _Job(lambda: direction_map(cloud, centre, params=params), delivered.append)
        job.start()
        time.sleep(min(0.2, whole / 4))  # well inside the computation
        return (job,), {}

    def cancel(job):
        job.cancel()
        job.thread.join()

    measure(cancel, rounds=5, setup=start)
    assert delivered == []  # no stale result
    benchmark.extra_info.update(n_points=n, whole_support_s=round(whole, 3))
