"""Start-up (1M points: first frame under 3 s): the launch imports the view's libraries
before Qt, and the first frame of a cloud needs none of the engine's heavy modules (scipy's KD-trees,
the metrics, gudhi, scikit-learn, the experiments), which ``skelcore`` imports on first use."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
ENGINE_ONLY = ("skelcore.stages", "skelcore.evaluation", "skelcore.metrics", "skelcore.experiments", "scipy.spatial",
               "scipy.sparse", "sklearn", "gudhi", "pandas", "numba")


def _python(code: str, *args: str, timeout: float = 300) -> subprocess.CompletedProcess:
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code), *args], capture_output=True, text=True,
                          cwd=ROOT, env=env, timeout=timeout)


def test_skelcore_imports_its_metrics_on_first_use_and_evaluate_is_the_function():
    out = _python(f"""
        import sys
        import skelcore, skelcore.io
        print(sorted(m for m in {ENGINE_ONLY!r} if m in sys.modules))
        from skelcore.stages import CORRESPONDENCE_CHOICES  # the stages first: skelcore.evaluate stays the function
        from skelcore import evaluate, shapes, Evaluation, skeletonize, load_cloud
        print(callable(skelcore.evaluate), skelcore.evaluate is evaluate, evaluate.__module__, shapes.__name__,
              Evaluation.__name__, callable(skeletonize), callable(load_cloud))
        ev = skelcore.evaluate(*(lambda s: (s.cloud, s.skeletal))(shapes.y_shape(300, seed=0)))
        print(type(ev).__name__)
    """)
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == "[]"
    assert lines[1] == "True True skelcore.stages.orchestrate skelcore.shapes Evaluation True True"
    assert lines[2] == "Evaluation"


@pytest.mark.gui
def test_the_launch_imports_with_the_collector_paused_and_the_first_frame_needs_no_engine(tmp_path):
    from skelcore import shapes
    from skelcore.io import write_points_ply

    cloud = tmp_path / "cloud.ply"
    write_points_ply(cloud, shapes.sphere_surface(20000, seed=0))
    out = _python(f"""
        import gc, sys
        from skelscope.__main__ import import_view_libraries
        import_view_libraries()
        print("skelscope.main_window" in sys.modules, gc.isenabled(), gc.get_freeze_count() > 10000)
        from PySide6 import QtCore, QtWidgets
        app = QtWidgets.QApplication(["startup-test"])
        import skelscope.main_window as window_module
        from skelscope.main_window import MainWindow
        window_module.preload_engine = lambda: None  # its timer could fire first on a loaded machine
        w = MainWindow(settings=QtCore.QSettings(sys.argv[2], QtCore.QSettings.Format.IniFormat))
        w.show()
        app.processEvents()
        painted = []
        w.view.plotter.ren_win.AddObserver("EndEvent", lambda *a: painted.append(1))
        assert w.session.load_as("cloud", sys.argv[1]), w.errors
        while not painted or w.view.render_pending:
            app.processEvents()
        print(w.scene.cloud.n_points, sorted(m for m in {ENGINE_ONLY!r} if m in sys.modules))
        w.close()
    """, str(cloud), str(tmp_path / "s.ini"))
    assert out.returncode == 0, out.stderr
    lines = out.stdout.splitlines()
    assert lines[0] == "True True True"  # imported with the collector paused, its objects frozen, collector back
    assert lines[1] == "20000 []"


def test_skelscope_main_imports_the_view_libraries_before_qt(tmp_path):
    """The real launch (``python -X importtime -m skelscope CLOUD --screenshot OUT --quit``): pyvista (VTK,
    matplotlib) has finished importing before PySide6 begins."""
    if not os.environ.get("DISPLAY"):
        pytest.skip("needs a display (pytest-xvfb)")
    from skelcore import shapes
    from skelcore.io import write_points_ply

    cloud = tmp_path / "cloud.ply"
    write_points_ply(cloud, shapes.sphere_surface(2000, seed=0))
    env = dict(os.environ, PYTHONPATH=str(ROOT) + os.pathsep + os.environ.get("PYTHONPATH", ""))
    # --size is checked before any window opens (app.view.camera): that must not import Qt either
    out = subprocess.run([sys.executable, "-X", "importtime", "-m", "skelscope", str(cloud), "--screenshot",
                          str(tmp_path / "out.png"), "--size", "320", "240", "--quit"], capture_output=True, text=True,
                         cwd=tmp_path, env=env, timeout=300)
    assert out.returncode == 0, out.stderr[-2000:]
    names = [line.rsplit("|", 1)[-1].strip() for line in out.stderr.splitlines() if line.startswith("import time:")]
    assert names.index("pyvista.plotting") < min(i for i, n in enumerate(names) if n.startswith(("shiboken6", "PySide6")))
