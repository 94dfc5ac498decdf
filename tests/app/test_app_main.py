"""``skelscope`` scripted use (exit codes, one-line errors, a real coloured screenshot) and the Tools
menu (skeletonize in the worker, the study dialog)."""

from __future__ import annotations

import sys

import numpy as np
import pytest
from PySide6 import QtCore, QtWidgets

from skelscope.__main__ import main
from skelcore import shapes
from shape_files import write_shape_files
from skelcore.io import write_points_ply

pytestmark = pytest.mark.gui


@pytest.fixture(scope="module")
def files(tmp_path_factory):
    return write_shape_files(tmp_path_factory.mktemp("scripted"), shapes.y_shape(900, seed=5))


@pytest.fixture
def no_user_settings(qapp, tmp_path, monkeypatch):
    """Scripted runs use a throwaway settings file and keep the test session's exception hook."""
    QtCore.QSettings.setPath(QtCore.QSettings.Format.NativeFormat, QtCore.QSettings.Scope.UserScope, str(tmp_path))
    monkeypatch.setattr(sys, "excepthook", sys.excepthook)


def test_scripted_run_evaluates_colours_saves_and_exits_0(files, tmp_path, capsys, no_user_settings):
    out = tmp_path / "smooth.png"
    code = main([files["cloud"], "--skeletal", files["skeletal"], "--curve", files["curve"],
                 "--metric", "smoothness", "--screenshot", str(out), "--quit"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert f"wrote {out}" in captured.out and "boundedness" in captured.out
    from matplotlib.image import imread

    img = (imread(out)[..., :3] * 255).round().astype(int).reshape(-1, 3)
    # smoothness is NaN at the Y's junction (degree 3) and tips (degree 1): magenta must be drawn
    assert np.all(img == [255, 0, 255], axis=1).sum() > 20
    assert (np.ptp(img, axis=1) <= 6).sum() > 1000  # and the grey cloud around it


def test_scripted_run_of_a_metric_without_invalid_values_has_no_magenta(tmp_path, capsys, no_user_settings):
    sh = shapes.cylinder(500, seed=2)
    write_points_ply(tmp_path / "c.ply", sh.cloud)
    write_points_ply(tmp_path / "s.ply", sh.skeletal)
    out = tmp_path / "bounded.png"
    code = main([str(tmp_path / "c.ply"), "--skeletal", str(tmp_path / "s.ply"), "--metric", "boundedness",
                 "--screenshot", str(out), "--scale", "2", "--quit"])
    assert code == 0, capsys.readouterr().err
    from matplotlib.image import imread

    img = (imread(out)[..., :3] * 255).round().astype(int).reshape(-1, 3)
    assert np.all(img == [255, 0, 255], axis=1).sum() == 0
    assert img.std() > 5


@pytest.mark.parametrize(
    "argv, message",
    [
        (["{missing}", "--screenshot", "{out}", "--quit"], "file not found"),
        (["--skeletal", "{skeletal}", "--quit"], "needs the cloud"),
        (["{cloud}", "--screenshot", "/no/such/folder/x.png", "--quit"], "output folder does not exist"),
        (["{cloud}", "--scale", "0", "--quit"], "--scale"),
    ],
)
def test_bad_input_exits_2_with_one_line_on_stderr(argv, message, files, tmp_path, capsys, no_user_settings):
    fill = dict(files, missing=str(tmp_path / "missing.ply"), out=str(tmp_path / "o.png"))
    code = main([a.format(**fill) for a in argv])
    err = capsys.readouterr().err
    assert code == 2 and message in err and err.count("\n") == 1


def test_unknown_metric_is_a_usage_error_exit_2(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["--metric", "roundness"])
    assert exc.value.code == 2 and capsys.readouterr().err.count("\n") == 1


@pytest.mark.window(auto_evaluate=True)
def test_skeletonize_action_runs_in_the_worker_and_loads_both_skeletons(window, qtbot, tmp_path):
    w = window
    assert not w.actions_by_name["skeletonize"].isEnabled()
    cloud = tmp_path / "cyl.ply"
    write_points_ply(cloud, shapes.cylinder(800, seed=1).cloud)
    w.session.load_as("cloud", str(cloud))
    assert w.actions_by_name["skeletonize"].isEnabled()
    w.session.auto_evaluate = False
    stages = []
    w.session.runner.progressed.connect(lambda f, s: stages.append(s))
    with qtbot.waitSignal(w.session.runner.succeeded, timeout=60000):
        w.actions_by_name["skeletonize"].trigger()
    assert w.scene.skeletal.n_points == 800 and w.scene.curve.curve.n_edges >= 1
    assert "contraction" in stages
    assert w.scene.skeletal.path is None and w.actions_by_name["evaluate"].isEnabled()


def test_study_action_opens_the_study_dialog_for_the_loaded_cloud(window, tmp_path):
    pytest.importorskip("skelscope.study_dialog")
    w = window
    cloud = tmp_path / "cyl.ply"
    write_points_ply(cloud, shapes.cylinder(500, seed=1).cloud)
    assert not w.actions_by_name["study"].isEnabled()
    w.session.load_as("cloud", str(cloud))
    assert w.actions_by_name["study"].isEnabled()
    w.actions_by_name["study"].trigger()
    assert w._study_dialog.cloud_path == str(cloud) and w._study_dialog.isVisible()
    w._study_dialog.close()


def test_an_uncaught_exception_becomes_a_dialog_with_the_traceback(window, monkeypatch):
    from skelscope.__main__ import _install_exception_hook

    shown = []
    monkeypatch.setattr(QtWidgets.QMessageBox, "exec", lambda self: shown.append((self.text(), self.detailedText())) or 0)
    monkeypatch.setattr(sys, "excepthook", sys.excepthook)
    w = window
    assert w.bug is None
    _install_exception_hook(w)
    try:
        1 / 0
    except ZeroDivisionError:
        sys.excepthook(*sys.exc_info())
    assert shown[0][0] == "ZeroDivisionError: division by zero" and "Traceback" in shown[0][1]
    assert w.isVisible() and w.bug is not None


def test_a_scripted_run_that_fails_closes_its_window(files, tmp_path, capsys, no_user_settings):
    """An error after the window was made (a missing file) returns 2 with the window closed: no window
    left holding the GUI thread's collector (app/gui_collector.py)."""
    from skelscope.gui_collector import gui_collector

    before = gui_collector().users
    shown = [w for w in QtWidgets.QApplication.topLevelWidgets() if w.isVisible()]
    assert main([str(tmp_path / "missing.ply"), "--screenshot", str(tmp_path / "o.png"), "--quit"]) == 2
    assert gui_collector().users == before
    assert [w for w in QtWidgets.QApplication.topLevelWidgets() if w.isVisible()] == shown
