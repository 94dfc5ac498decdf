"""Saved sessions: File > Save session / Open session and ``skelscope --session F`` restore
the files, settings and thresholds, correspondence mode, metric, colour range, display options, camera
and picked element from one small versioned JSON file; paths relative to it; files that moved or
changed are named in ONE dialog and the rest is loaded; a bad file is a one-line dialog and nothing
changes; File > Recent lists sets and sessions, not single files."""

from __future__ import annotations

import json
import os
import shutil

import numpy as np
import pytest
from PySide6 import QtCore

from shape_files import write_shape_files
from skelcore import shapes
from skelcore.io import write_points_ply
from skelcore.params import Params

pytestmark = [pytest.mark.gui, pytest.mark.window(size=(1200, 800), dialogs="record")]


@pytest.fixture
def files(tmp_path):
    folder = tmp_path / "data"
    folder.mkdir()
    return write_shape_files(folder, shapes.y_shape(1200, seed=3))


def _load(window, files):
    window.session.load_files([files["cloud"], files["skeletal"], files["curve"]])


def _wait_evaluated(window, qtbot):
    qtbot.waitUntil(lambda: window.scene.evaluation is not None and not window.session.runner.running, timeout=60000)


def _dress(window):
    """A state far from the defaults: settings, thresholds, correspondence, display, camera."""
    w = window
    w.set_settings(Params(normalize_by="diagonal", tangent_k=10, smooth_k=5, curve_samples=150, beta_star=0.6,
                          c_star=0.7), "reverse")
    s = w.scene
    s.set_metric("centeredness")
    s.set_clim((0.2, 0.9))
    s.set_edges_as_tubes(True)
    s.set_style("spheres", True)
    s.set_style("axes", False)
    s.set_opacity("cloud", 0.5)
    s.set_point_size("skeletal", 9)
    s.set_visible("curve", False)
    w.view.standard_view("xz")


def _state(window) -> dict:
    s = window.scene
    cam = window.view.camera_state()
    return {
        "files": s.input_paths(), "params": window.session.params(), "corr": window.session.correspondence_provider(),
        "metric": s.metric, "clim": s.clim, "tubes": s.edges_as_tubes, "style": dict(s.style),
        "layers": {r: (l.visible, l.point_size, l.opacity) for r, l in s.layers.items()},
        "camera": [np.round(cam[k], 6).tolist() for k in ("position", "focal_point", "view_up")],
    }


@pytest.mark.window(auto_evaluate=True, dialogs="record")
def test_a_saved_session_restores_everything_and_is_small_versioned_json_with_relative_paths(window, files, tmp_path,
                                                                                          qtbot):
    w = window
    _load(w, files)
    _wait_evaluated(w, qtbot)
    _dress(w)
    w.session.start_evaluation()  # with the dressed settings
    _wait_evaluated(w, qtbot)
    picked = w.select_element("skeletal", "points", 17)
    assert w.picked_element()["index"] == 17
    before = _state(w)
    path = str(tmp_path / "y_session.json")
    w.saved_sessions.save(path)
    doc = json.loads(open(path).read())
    assert doc["skelscope_session"] == 1 and os.path.getsize(path) < 8000
    assert doc["files"]["cloud"]["relative"] == os.path.join("data", "y_cloud.ply")
    assert doc["files"]["skeletal"]["sha256"] and doc["files"]["curve"]["size"] == os.path.getsize(files["curve"])
    assert doc["params"]["beta_star"] == 0.6 and doc["correspondence"] == "reverse"
    assert doc["picked"] == {"layer": "skeletal", "location": "points", "index": 17}
    assert doc["camera"]["view_size"] == list(w.view.plotter.render_window.GetSize())

    # everything back to defaults, then the session
    w.session.close_all()
    w.set_settings(Params(), "auto")
    for name, on in (("spheres", False), ("axes", True)):
        w.scene.set_style(name, on)
    w.scene.set_metric("boundedness")
    w.scene.set_clim(None)
    w.scene.set_edges_as_tubes(False)
    assert w.saved_sessions.open(path) == []
    _wait_evaluated(w, qtbot)
    assert _state(w) == before
    assert w.settings_panel.correspondence() == "reverse" and w.summary.beta_star.value() == 0.6
    # the pick lands once the evaluation has (it clears the pick panel), with its values, marked in 3D
    qtbot.waitUntil(lambda: w.picked_element() is not None, timeout=30000)
    assert w.picked_element()["index"] == 17 and w.picked_element()["values"] == picked["values"]
    assert "pick-marker" in w.view._actors
    assert w.dialogs == []


def test_a_session_moved_with_its_data_finds_its_files_beside_it(window, files, tmp_path):
    _load(window, files)
    path = tmp_path / "y_session.json"
    window.saved_sessions.save(str(path))
    window.session.close_all()
    moved = tmp_path.parent / (tmp_path.name + "_moved")
    shutil.move(str(tmp_path), str(moved))
    try:
        assert window.saved_sessions.open(str(moved / "y_session.json")) == []
        assert window.scene.input_paths()["curve"] == str(moved / "data" / "y_curve.ply")
        assert window.dialogs == []
    finally:
        shutil.move(str(moved), str(tmp_path))


def test_files_that_moved_or_changed_are_named_in_one_dialog_and_the_rest_is_loaded(window, files, tmp_path):
    w = window
    _load(w, files)
    w.select_element("curve", "vertices", 2)
    path = str(tmp_path / "y_session.json")
    w.saved_sessions.save(path)
    os.remove(files["curve"])
    sh = shapes.y_shape(1200, seed=4)  # the same point count: the same file size, other content
    size = os.path.getsize(files["skeletal"])
    write_points_ply(tmp_path / "other.ply", sh.skeletal)  # another tool rewrites the file
    os.replace(tmp_path / "other.ply", files["skeletal"])
    assert os.path.getsize(files["skeletal"]) == size
    w.session.close_all()
    problems = w.saved_sessions.open(path)
    assert len(w.dialogs) == 1, w.dialogs  # ONE dialog
    text = w.dialogs[0]
    assert "y_curve.ply: missing" in text and "y_skeletal.ply: changed" in text and "y_cloud.ply" not in text
    assert "picked element (curve #2)" in text  # its layer could not be loaded
    assert len(problems) == 3
    assert set(w.scene.layers) == {"cloud", "skeletal"}
    np.testing.assert_allclose(w.scene.skeletal.points, sh.skeletal)  # the file as it is now
    # touched but not changed (a copy, a backup tool): no word about it
    w.dialogs.clear()
    w.saved_sessions.save(path)
    stamp = os.path.getmtime(files["cloud"]) + 100
    os.utime(files["cloud"], (stamp, stamp))
    assert w.saved_sessions.open(path) == [] and w.dialogs == []


@pytest.mark.parametrize("content, says", [
    ("{not json", "not a SkelScope session file"),
    ('{"files": {}}', "no 'skelscope_session' key"),
    ('{"skelscope_session": 7}', "version 7 is newer"),
    ('{"skelscope_session": 1, "params": {"beta_star": 2.5}}', "bad parameters"),
    ('{"skelscope_session": 1, "params": {"no_such": 1}}', "unknown parameter(s) no_such"),
    ('{"skelscope_session": 1, "metric": "beauty"}', "metric must be one of"),
    ('{"skelscope_session": 1, "files": {"cloud": {"path": "x.ply"}}}', "the cloud file record needs"),
    ('{"skelscope_session": 1, "camera": {"position": [0, 0]}}', "the camera needs"),
    ('{"skelscope_session": 1, "scan_options": {"remove_outliers": "yes"}}', "scan_options must map"),
])
def test_a_bad_session_file_is_a_one_line_dialog_and_nothing_changes(window, files, tmp_path, content, says):
    w = window
    _load(w, files)
    w.scene.set_metric("smoothness")
    w.set_settings(Params(tangent_k=11), "auto")
    before = _state(w)
    bad = tmp_path / "bad_session.json"
    bad.write_text(content)
    problems = w.saved_sessions.open(str(bad))
    assert len(w.dialogs) == 1 and "\n" not in w.dialogs[0], w.dialogs
    assert w.dialogs[0].startswith(str(bad)) and says in w.dialogs[0], w.dialogs[0]
    assert problems == w.dialogs
    assert _state(w) == before


def test_recent_lists_sets_and_sessions_not_single_files(window, files, tmp_path):
    w = window
    sessions = w.saved_sessions
    w.session.load_as("cloud", files["cloud"])
    w.session.load_as("skeletal", files["skeletal"])
    w.session.load_as("curve", files["curve"])
    QtCore.QCoreApplication.processEvents()
    entries = sessions.recent()
    assert entries == [{"files": {r: os.path.abspath(files[r]) for r in ("cloud", "skeletal", "curve")}}]
    menu = w.submenu("file.recent")
    assert [a.text() for a in menu.actions()] == ["y_cloud.ply + y_skeletal.ply + y_curve.ply"]
    other = write_shape_files(tmp_path, shapes.y_shape(500, seed=9), stem="z")
    w.session.close_all()
    w.session.load_files([other["cloud"], other["skeletal"]])
    QtCore.QCoreApplication.processEvents()
    path = str(tmp_path / "z_session.json")
    sessions.save(path)
    assert [a.text() for a in menu.actions()] == [
        "z_session.json (session)", "z_cloud.ply + z_skeletal.ply", "y_cloud.ply + y_skeletal.ply + y_curve.ply"]
    # choosing a set loads it whole, in place of what is loaded
    menu.actions()[2].trigger()
    assert w.scene.input_paths() == {r: files[r] for r in ("cloud", "skeletal", "curve")}
    assert w.dialogs == []
    QtCore.QCoreApplication.processEvents()
    assert [a.text() for a in menu.actions()][0] == "y_cloud.ply + y_skeletal.ply + y_curve.ply"  # newest again
    assert len(menu.actions()) == 3
    # a set whose file is gone: the rest loads, one dialog names it
    os.remove(other["skeletal"])
    next(a for a in menu.actions() if a.text() == "z_cloud.ply + z_skeletal.ply").trigger()
    assert set(w.scene.layers) == {"cloud"} and len(w.dialogs) == 1 and "z_skeletal.ply: missing" in w.dialogs[0]
    # a session entry opens the session
    w.dialogs.clear()
    next(a for a in menu.actions() if a.text() == "z_session.json (session)").trigger()
    assert len(w.dialogs) == 1 and "z_skeletal.ply: missing" in w.dialogs[0]


def test_a_session_needs_files_and_is_written_atomically_never_over_an_input(window, files, tmp_path):
    w = window
    w.session.show_arrays(shapes.y_shape(300, seed=1).cloud)  # a study variant: in memory only
    with pytest.raises(ValueError, match="exist only in memory"):
        w.saved_sessions.save(str(tmp_path / "s.json"))
    _load(w, files)
    with pytest.raises(Exception, match="refusing to overwrite an input"):
        w.saved_sessions.save(files["cloud"])
    assert os.path.getsize(files["cloud"]) > 1000  # untouched
    assert w.actions_by_name["save_session"].isEnabled() and w.actions_by_name["open_session"].isEnabled()
    file_menu = w.menuBar().actions()[0].menu()
    texts = [a.text() for a in file_menu.actions() if not a.isSeparator()]
    assert texts.index("Open session…") < texts.index("Save session…") < texts.index("Recent")


def test_skelscope_session_restores_it_in_the_scripted_mode(window, files, tmp_path, capsys, monkeypatch):
    import sys

    from matplotlib.image import imread

    from skelscope.__main__ import main

    w = window
    _load(w, files)
    w.scene.set_metric("smoothness")
    w.view.standard_view("xz")
    path = str(tmp_path / "y_session.json")
    w.saved_sessions.save(path)
    size = tuple(w.view.plotter.render_window.GetSize())
    QtCore.QSettings.setPath(QtCore.QSettings.Format.NativeFormat, QtCore.QSettings.Scope.UserScope, str(tmp_path))
    monkeypatch.setattr(sys, "excepthook", sys.excepthook)
    out = tmp_path / "s.png"
    assert main(["--session", path, "--screenshot", str(out), "--quit"]) == 0, capsys.readouterr().err
    printed = capsys.readouterr().out
    assert "smoothness" in printed
    img = imread(str(out))
    assert img.shape[:2] == (size[1], size[0])  # the session's view size: its framing
    # bad ones: one line, exit 2, before any window
    (tmp_path / "bad.json").write_text("[]")
    assert main(["--session", str(tmp_path / "bad.json"), "--quit"]) == 2
    assert "bad.json: not a SkelScope session file" in capsys.readouterr().err
    assert main(["--session", path, files["cloud"], "--quit"]) == 2
    assert "--session names its own files" in capsys.readouterr().err
    # a missing file: a warning line on stderr, the rest is loaded and pictured
    os.remove(files["curve"])
    assert main(["--session", path, "--screenshot", str(out), "--quit"]) == 0
    assert "skelscope: warning: y_curve.ply: missing" in capsys.readouterr().err


@pytest.mark.window(auto_evaluate=True, dialogs="record")
def test_a_session_keeps_the_skeletal_index_the_mapping_and_the_viewpoints(window, tmp_path, qtbot):
    """A skeletal set of every third point with its index file, both skeleton layers in
    another frame (a tenth the size, shifted) mapped back by scale 10 and an offset, and a viewpoint:
    saved, then restored as they were and evaluated with them; a moved index is named in the one dialog."""
    from skelcore.curve import CurveSkeleton
    from skelcore.io import write_curve_ply

    w = window
    folder = tmp_path / "data"
    folder.mkdir()
    sh = shapes.y_shape(1200, seed=3)
    files = write_shape_files(folder, sh)
    rows = np.arange(1, len(sh.skeletal), 3)
    shift = np.array([5.0, -2.0, 1.0])
    write_points_ply(folder / "y_sub.ply", sh.skeletal[rows] / 10 + shift)
    write_curve_ply(folder / "y_small_curve.ply", sh.curve_vertices / 10 + shift, sh.curve_edges)
    (folder / "y_sub.idx").write_text("\n".join(map(str, rows)) + "\n")
    w.session.load_as("cloud", files["cloud"])
    w.session.load_as("skeletal", str(folder / "y_sub.ply"))
    w.session.load_as("curve", str(folder / "y_small_curve.ply"))
    assert w.session.load_index(str(folder / "y_sub.idx"))
    offset = tuple(-10 * shift)
    assert w.session.map_skeleton(10.0, offset)
    assert w.viewpoints.set_text("0 0 5")
    _wait_evaluated(w, qtbot)
    path = str(tmp_path / "mapped_session.json")
    w.saved_sessions.save(path)
    doc = json.loads(open(path).read())
    assert doc["skeletal_index"]["relative"] == os.path.join("data", "y_sub.idx") and doc["skeletal_index"]["sha256"]
    assert doc["mappings"]["skeletal"] == doc["mappings"]["curve"] == {"scale": 10.0, "offset": list(offset)}
    assert doc["viewpoints"] == [[0.0, 0.0, 5.0]]

    w.session.close_all()
    w.session.viewpoints = []
    assert w.saved_sessions.open(path) == [] and w.dialogs == []
    sk, cv = w.scene.skeletal, w.scene.curve
    np.testing.assert_array_equal(sk.index, rows)
    assert sk.index_path == str(folder / "y_sub.idx")
    assert sk.mapping == cv.mapping == (10.0, offset)
    np.testing.assert_allclose(sk.points, sh.skeletal[rows], atol=1e-9)  # back in the cloud's frame
    np.testing.assert_allclose(cv.points, CurveSkeleton.from_raw(sh.curve_vertices, sh.curve_edges).vertices, atol=1e-9)
    assert w.session.viewpoints == [(0.0, 0.0, 5.0)]
    _wait_evaluated(w, qtbot)
    ev = w.scene.evaluation
    assert ev.correspondence == "index" and ev.scan.viewpoints == [[0.0, 0.0, 5.0]]
    assert w.session.stale_reason() == ""

    # the index moved away: named in the one dialog, the rest restored
    os.replace(folder / "y_sub.idx", tmp_path / "elsewhere.idx")
    w.session.close_all()
    problems = w.saved_sessions.open(path)
    assert len(w.dialogs) == 1 and len(problems) == 1
    assert "y_sub.idx: missing (the skeletal index" in w.dialogs[0]
    assert w.scene.skeletal.index is None and w.scene.skeletal.mapping == (10.0, offset)


@pytest.mark.window(size=None, dialogs="record")  # the window's own size: it fits the screen
def test_skelscope_session_opened_for_the_user_fits_the_screen_it_was_not_saved_on(window, files, tmp_path):
    """A session saved on a larger screen (its 3-D view 1485 x 950): ``skelscope --session F`` opens a
    window that fits this screen, as File > Open session does; only a scripted picture takes the saved
    view size (it frames the picture as it was framed)."""
    from skelscope.__main__ import build_parser
    from skelscope.scripted import check_arguments, run

    w = window
    _load(w, files)
    path = str(tmp_path / "big_session.json")
    w.saved_sessions.save(path)
    doc = json.loads(open(path).read())
    doc["camera"]["view_size"] = [1485, 950]
    open(path, "w").write(json.dumps(doc))
    w.session.close_all()
    free = w.screen().availableGeometry()
    assert free.width() < 1485 or free.height() < 950  # this screen is smaller than the saved one
    startup = check_arguments(build_parser().parse_args(["--session", path]))
    assert startup.view_size is None
    app = QtCore.QCoreApplication.instance()
    assert run(app, w, startup) is None  # the event loop would run: an interactive launch
    assert w.scene.cloud is not None and free.contains(w.frameGeometry()), (w.frameGeometry(), free)
    assert w.dialogs == []
    # the scripted picture keeps the saved size; --size is the user's
    shot = str(tmp_path / "s.png")
    assert check_arguments(build_parser().parse_args(["--session", path, "--screenshot", shot])).view_size == (1485, 950)
    assert check_arguments(build_parser().parse_args(["--session", path, "--size", "300", "200"])).view_size == (300, 200)


def test_open_session_starts_in_the_sessions_folder_not_the_last_data_folder(window, files, tmp_path, monkeypatch):
    from PySide6 import QtWidgets

    w = window
    _load(w, files)
    kept = tmp_path / "sessions"
    kept.mkdir()
    w.saved_sessions.save(str(kept / "y_session.json"))
    other = tmp_path / "other_data"
    shutil.copytree(os.path.dirname(files["cloud"]), other)
    w.session.load_files([str(other / os.path.basename(files["cloud"]))])  # newer data, elsewhere
    assert w.last_dir() == str(other)
    asked = []
    monkeypatch.setattr(QtWidgets.QFileDialog, "getOpenFileName",
                        lambda parent, title, folder, *a, **k: asked.append((title, folder)) or ("", ""))
    w.saved_sessions.open_dialog()
    assert asked == [("Open session", str(kept))]


def test_a_session_keeps_reverse_projection_for_its_mapped_set_of_another_size(window, files, tmp_path):
    """The correspondence chosen for a set of another size is restored with that set, also when the
    set is mapped into the cloud's frame on restoring (a new layer of the same set)."""
    from skelcore.io import load_points

    from skelscope.loading import SKELETAL_REVERSE

    w = window
    sub = tmp_path / "sub.ply"
    write_points_ply(sub, load_points(files["skeletal"])[::3] / 2.0)
    w.session.load_files([files["cloud"]])
    w.session.ask = lambda question, options: SKELETAL_REVERSE
    w.session.load_files([str(sub)])
    assert w.session.map_skeleton(2.0, (0.0, 0.0, 0.0))
    assert w.settings_panel.correspondence() == "reverse"
    path = str(tmp_path / "sub_session.json")
    w.saved_sessions.save(path)
    w.session.close_all()
    w.set_settings(Params(), "auto")
    assert w.saved_sessions.open(path) == []
    assert w.scene.skeletal.mapping[0] == pytest.approx(2.0)
    assert w.settings_panel.correspondence() == "reverse"
