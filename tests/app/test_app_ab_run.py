"""A ``skelcore compare`` run's report rows open in the A/B view from their stored results
(File > Open comparison run, drops, ``--compare-run``), ``--skeleton-b``, one-line errors, and the
skeletal support under the "index" correspondence."""

from __future__ import annotations

import json
import shutil
import sys

import numpy as np
import pytest
from PySide6 import QtCore, QtGui, QtWidgets

from skelscope.__main__ import main
from compare_helpers import make_dataset, manifest
from shape_files import write_shape_files
from skelcore import evaluate, shapes
from skelcore.compare import Backend, run_compare
from skelcore.compare.jobs import execute, make_jobs
from skelcore.compare.manifest import load_manifest
from skelcore.io import load_points, write_points_ply
from skelcore.params import k_center_for

pytestmark = [pytest.mark.gui, pytest.mark.window(size=(1200, 800), dialogs="record")]

BODY = """
[[shapes]]
path = "clouds/*.ply"
[[methods]]
name = "truth"
kind = "files"
curve = "skeletons/{stem}_curve.ply"
skeletal = "skeletons/{stem}_skeletal.ply"
[[methods]]
name = "sub"
kind = "files"
skeletal = "skeletons/{stem}_sub.ply"
skeletal_index = "skeletons/{stem}_sub.idx"
[[methods]]
name = "builtin"
kind = "builtin"
[[conditions]]
name = "normal"
"""


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    root = make_dataset(tmp_path_factory.mktemp("abrun"), n=600)
    for stem in ("cyl", "yshape"):  # every third true skeletal point, with its cloud rows as the index
        sk = load_points(root / "skeletons" / f"{stem}_skeletal.ply")
        rows = np.arange(1, len(sk), 3)
        write_points_ply(root / "skeletons" / f"{stem}_sub.ply", sk[rows])
        (root / "skeletons" / f"{stem}_sub.idx").write_text("\n".join(map(str, rows)) + "\n")
    m = manifest(root, BODY)
    assert run_compare(m, root / "out", Backend("serial"), report=False).summary.failed == 0
    return root, m, root / "out"


@pytest.fixture
def errors(window):
    return window.dialogs  # the error dialogs' lines


@pytest.fixture
def no_user_settings(qapp, tmp_path, monkeypatch):
    QtCore.QSettings.setPath(QtCore.QSettings.Format.NativeFormat, QtCore.QSettings.Scope.UserScope, str(tmp_path))
    monkeypatch.setattr(sys, "excepthook", sys.excepthook)


def _no_evaluation(monkeypatch):
    """Opening stored results must not evaluate anything."""
    import skelcore

    engine = sys.modules["skelcore.stages"]  # where the compare jobs import evaluate from

    def refuse(*_a, **_k):
        raise AssertionError("an evaluation ran: stored results must be shown as they are")

    monkeypatch.setattr(skelcore, "evaluate", refuse)
    monkeypatch.setattr(engine, "evaluate", refuse)


def _fresh(m, shape: str, method: str):
    job = next(j for j in make_jobs(load_manifest(m)) if j.shape.name == shape and j.method.name == method)
    return execute(job).evaluation


def test_the_dialog_lists_the_reports_rows_and_opens_the_ab_view_from_stored_results(window, run_dir, monkeypatch):
    from skelscope.compare_view import ab_rows

    _root, m, out = run_dir
    assert "open_compare_run" in window.actions_by_name
    dialog = window.compare_run.open(out)
    assert [dialog.dataset.itemText(i) for i in range(dialog.dataset.count())] == ["cyl", "yshape"]
    dialog.select(dataset="yshape", a="truth", b="builtin")
    assert dialog.table.rowCount() == 3
    assert [dialog.table.item(r, 2).text() for r in range(3)] == ["ok"] * 3
    assert [dialog.table.item(r, 0).text() for r in range(3)] == ["A", "", "B"]  # truth, sub, builtin
    assert dialog.choice() == ("yshape", "normal", 0, "truth", "builtin")
    # the A/B table's differences are those of the two evaluations, computed afresh here
    expected = ab_rows(_fresh(m, "yshape", "truth").summary(), _fresh(m, "yshape", "builtin").summary())
    _no_evaluation(monkeypatch)
    view = dialog.open_ab()
    assert view is not None and view.isVisible() and not window.session.runner.running
    assert "yshape, normal, seed 0" in view.windowTitle()
    assert len(view.rows) == len(expected) == 10  # 8 of the paper, 2 coverage rows (SkelScope's own)
    for (label, a, b, d), (label2, a2, b2, d2) in zip(view.rows, expected):
        assert label == label2 and a == pytest.approx(a2, abs=1e-12) and b == pytest.approx(b2, abs=1e-12)
        assert d == pytest.approx(d2, abs=1e-12)
    row = [r[0] for r in view.rows].index("centeredness (curve)")
    assert view.cell(row, 3) == f"{expected[row][3]:+.4f}"
    img = view.image()
    half = img.shape[1] // 2
    for part in (img[:, :half], img[:, half:]):  # both skeletons drawn, coloured
        rgb = part[..., :3].reshape(-1, 3).astype(int)
        assert (np.ptp(rgb, axis=1) > 60).sum() > 200


def test_a_big_runs_rows_are_read_in_a_thread_and_the_newest_request_wins(window, run_dir, qtbot, errors):
    _root, _m, out = run_dir
    dialog = window.compare_run.open(out)
    dialog.background_bytes = 0  # every run is "big"
    dialog.select(dataset="cyl", a="truth", b="sub")
    assert dialog.show_a() is None and dialog.busy and not dialog.open_button.isEnabled()
    dialog.select(dataset="yshape", a="truth", b="builtin")
    assert dialog.open_ab() is None  # replaces the first request, whose result must not land
    qtbot.waitUntil(lambda: not dialog.busy, timeout=20000)
    assert len(window.compare.views) == 1 and dialog.view is window.compare.views[0]
    assert "yshape" in dialog.view.windowTitle() and window.scene.evaluation is None
    assert dialog.open_button.isEnabled() and errors == []
    dialog.select(dataset="cyl", a="truth", b="builtin", condition="normal")
    bad = dialog.run.find("cyl", "builtin")
    (out / "jobs" / f"{bad.key}.npz").rename(out / "jobs" / "moved.npz")
    try:
        dialog.open_ab()
        qtbot.waitUntil(lambda: not dialog.busy, timeout=20000)
    finally:
        (out / "jobs" / "moved.npz").rename(out / "jobs" / f"{bad.key}.npz")
    assert len(errors) == 1 and "its arrays are missing" in errors[0]


def test_show_a_puts_the_stored_index_result_in_the_main_window_and_its_support_draws(window, run_dir, monkeypatch):
    root, _m, out = run_dir
    dialog = window.compare_run.open(out / "index.json")
    dialog.select(dataset="cyl", a="sub", b="truth")
    _no_evaluation(monkeypatch)
    assert dialog.show_a()
    ev = window.scene.evaluation
    assert ev is not None and ev.correspondence == "index"
    idx = np.loadtxt(root / "skeletons" / "cyl_sub.idx", dtype=np.int64)
    window.scene.set_metric("centeredness")
    i = int(np.argmin(np.abs(ev.skeletal.points[:, 2] - 2.0)))
    window.pick_element(window.scene.element_info("skeletal", "points", i))
    sup = window.supports.support
    assert sup.kind == "knn", sup.reason
    assert sup.value == pytest.approx(ev.skeletal.centeredness_raw[i], abs=1e-12)
    np.testing.assert_array_equal(sup.points3d["cloud"], ev.cloud[idx[sup.detail.neighbours]])
    assert dialog.show_b()  # B's stored result replaces it
    assert window.scene.evaluation.correspondence == "pointwise" and window.scene.curve is not None


def test_skeletal_support_under_a_skeletal_index_matches_eq10_by_hand(window):
    """Known answer: each skeletal point is its cloud row's projection onto the cylinder's axis, so
    the corresponding cloud points have the neighbours' heights and lie at the radius; the value is
    paper Eq. 10 computed here with a plain loop."""
    cyl = shapes.cylinder(1800, radius=0.5, length=4.0, capped=False, seed=6)
    rng = np.random.default_rng(1)
    index = rng.permutation(len(cyl.cloud))[:500]  # 500 skeletal points, shuffled cloud rows
    skeletal = cyl.skeletal[index]
    ev = evaluate(cyl.cloud, skeletal, skeletal_index=index)
    assert ev.correspondence == "index"
    np.testing.assert_array_equal(ev.skeletal.index, index)
    window.session.show_arrays(cyl.cloud, skeletal, None, ev)
    window.scene.set_metric("centeredness")
    for i in (0, 123, 499):
        window.pick_element(window.scene.element_info("skeletal", "points", i))
        sup = window.supports.support
        assert sup.kind == "knn", sup.reason
        nb = sup.detail.neighbours
        corr = sup.points3d["cloud"]
        np.testing.assert_allclose(corr[:, 2], skeletal[nb, 2], atol=1e-12)
        np.testing.assert_allclose(np.linalg.norm(corr[:, :2], axis=1), 0.5, atol=1e-9)
        # Eq. 10 by hand, in normalized units (ties by row, as the engine)
        s_n, o_n = ev.normalization.apply(skeletal), ev.normalization.apply(cyl.cloud[index])
        k = k_center_for(len(skeletal), ev.params)
        d = [float(np.sqrt(((s_n[j] - s_n[i]) ** 2).sum())) for j in range(len(s_n))]
        near = sorted(range(len(s_n)), key=lambda j: (d[j], j))[:k]
        m_s = sum(s_n[j] for j in near) / k
        m_o = sum(o_n[j] for j in near) / k
        spread = sum(float(np.linalg.norm(o_n[j] - m_s)) for j in near) / k
        assert sorted(nb.tolist()) == sorted(near)
        assert sup.value == pytest.approx(max(0.0, 1 - float(np.linalg.norm(m_o - m_s)) / spread), abs=1e-12)
        assert sup.value == pytest.approx(ev.skeletal.centeredness_raw[i], abs=1e-12)
    assert {"support-neighbours", "support-cloud", "support-m_s", "support-m_o"} <= set(window.supports.overlay.names)


def _drop(widget, path, qtbot) -> bool:
    mime = QtCore.QMimeData()
    mime.setUrls([QtCore.QUrl.fromLocalFile(str(path))])
    pos = QtCore.QPointF(50, 50)
    buttons, mods = QtCore.Qt.MouseButton.LeftButton, QtCore.Qt.KeyboardModifier.NoModifier
    enter = QtGui.QDragEnterEvent(pos.toPoint(), QtCore.Qt.DropAction.CopyAction, mime, buttons, mods)
    QtWidgets.QApplication.sendEvent(widget, enter)
    accepted = enter.isAccepted()
    drop = QtGui.QDropEvent(pos, QtCore.Qt.DropAction.CopyAction, mime, buttons, mods)
    QtWidgets.QApplication.sendEvent(widget, drop)
    qtbot.wait(50)
    return accepted


def test_dropping_a_run_folder_or_its_index_opens_the_dialog(window, run_dir, qtbot, errors):
    _root, _m, out = run_dir
    assert _drop(window.view.plotter, out, qtbot)  # on the 3-D view
    assert window.compare_run.dialog is not None and window.compare_run.dialog.run.root == out
    window.compare_run.dialog.close()
    window.compare_run.dialog = None
    assert _drop(window, out / "index.json", qtbot)  # on the window itself
    dialog = window.compare_run.dialog
    assert dialog is not None and dialog.isVisible()
    assert errors == [] and window.scene.cloud is None  # nothing was loaded as a cloud
    window.closing.emit()  # the main window closing: the run's dialog goes with it
    assert not dialog.isVisible() and window.compare_run.dialog is None


def test_a_dropped_folder_that_is_not_a_run_is_refused_in_one_line_naming_it(window, tmp_path, qtbot, errors):
    """A folder of data files (no index.json, no jobs/) dropped on the window: taken (not a silent
    no-op), then one dialog line naming the folder and what a run's folder holds; nothing is loaded."""
    folder = tmp_path / "scans"
    folder.mkdir()
    write_points_ply(folder / "cloud.ply", shapes.sphere_surface(200, seed=0))
    assert _drop(window, folder, qtbot)
    qtbot.waitUntil(lambda: errors != [], timeout=5000)
    assert len(errors) == 1 and "\n" not in errors[0], errors
    assert errors[0].startswith("scans: ") and "not a skelcore compare run" in errors[0]
    assert window.scene.cloud is None and window.compare_run.dialog is None


def test_bad_runs_and_failed_jobs_are_one_line_dialogs(window, run_dir, tmp_path, errors):
    _root, _m, out = run_dir
    assert window.compare_run.open(tmp_path / "missing") is None
    assert len(errors) == 1 and "no such folder" in errors[0] and "\n" not in errors[0]
    copy = tmp_path / "copy"
    shutil.copytree(out, copy)
    dialog = window.compare_run.open(copy)
    job = dialog.run.find("cyl", "builtin")
    rec_path = copy / "jobs" / f"{job.key}.json"
    rec = json.loads(rec_path.read_text())
    rec.update(status="failed", error="MemoryError: out of memory")
    rec_path.write_text(json.dumps(rec))
    npz = copy / "jobs" / f"{dialog.run.find('cyl', 'truth').key}.npz"
    with np.load(npz) as z:
        old = {k: z[k] for k in z.files if not k.startswith("ev_")}
    with open(npz, "wb") as fh:
        np.savez_compressed(fh, **old)
    dialog.select(dataset="yshape")
    dialog.select(dataset="cyl", a="truth", b="builtin")
    statuses = {dialog.table.item(r, 1).text(): dialog.table.item(r, 2).text() for r in range(dialog.table.rowCount())}
    assert statuses["builtin"] == "failed: MemoryError: out of memory"
    assert dialog.open_ab() is None
    assert "stored no skeletons" in errors[-1] and "\n" not in errors[-1]
    dialog.select(a="sub", b="builtin")
    assert dialog.open_ab() is None
    assert "cyl / builtin / normal / seed 0 failed: MemoryError" in errors[-1]
    assert window.compare.views == []


def test_compare_run_on_the_command_line_saves_the_ab_view(run_dir, tmp_path, capsys, no_user_settings, monkeypatch):
    _root, _m, out = run_dir
    png = tmp_path / "ab.png"
    _no_evaluation(monkeypatch)
    code = main(["--compare-run", str(out), "--dataset", "yshape", "--a", "truth", "--b", "builtin",
                 "--metric", "centeredness", "--screenshot", str(png), "--quit"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert f"wrote {png}" in captured.out and "centeredness (curve)" in captured.out and "B-A" in captured.out
    from matplotlib.image import imread

    img = (imread(png)[..., :3] * 255).round().astype(int)
    from skelscope.compare_view import AB_SIZE

    assert img.shape[:2] == (AB_SIZE[1], AB_SIZE[0])  # the same picture on any screen (this one is smaller)
    assert (np.ptp(img.reshape(-1, 3), axis=1) > 60).sum() > 500  # coloured skeletons


@pytest.mark.parametrize("argv, message", [
    (["--compare-run", "{missing}", "--a", "truth", "--b", "builtin"], "no such folder"),
    (["--compare-run", "{out}", "--dataset", "torus", "--a", "truth", "--b", "builtin"],
     "unknown dataset 'torus': the run has 'cyl', 'yshape'"),
    (["--compare-run", "{out}", "--a", "truth", "--b", "lbc"], "unknown method 'lbc'"),
    (["--compare-run", "{out}", "--a", "truth"], "--compare-run needs --a METHOD and --b METHOD"),
    (["--dataset", "cyl"], "--dataset goes with --compare-run DIR"),
    (["--compare-run", "{out}", "--a", "truth", "--b", "sub", "{cloud}"], "give no CLOUD"),
    (["{cloud}", "--skeleton-b", "{cloud}"], "--skeleton-b needs CLOUD and skeleton A"),
    (["{cloud}", "--skeletal", "{skeletal}", "--skeleton-b", "{missing}"], "missing"),
    (["{cloud}", "--skeletal", "{skeletal}", "--skeleton-b", "{skeletal}", "--skeleton-b", "{skeletal}"],
     "--skeleton-b: two skeletal files"),
])
def test_bad_ab_arguments_exit_2_with_one_line(argv, message, run_dir, tmp_path, capsys):
    _root, _m, out = run_dir
    files = write_shape_files(tmp_path, shapes.y_shape(300, seed=1))
    subs = {"{out}": str(out), "{missing}": str(tmp_path / "missing"), "{cloud}": files["cloud"],
            "{skeletal}": files["skeletal"]}
    code = main([subs.get(a, a) for a in argv])
    err = capsys.readouterr().err
    assert code == 2
    assert err.count("\n") == 1 and err.startswith("skelscope: error:") and message in err, err


def test_an_option_prefix_is_not_taken_for_skeleton_b(capsys):
    """argparse would read "--skeleton F" as "--skeleton-b F" and open the A/B view: it is an error."""
    from skelscope.__main__ import build_parser

    with pytest.raises(SystemExit) as exc:
        build_parser().parse_args(["cloud.ply", "--skeleton", "skel.ply"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.count("\n") == 1 and "unrecognized arguments: --skeleton skel.ply" in err


def test_skeleton_b_on_the_command_line_is_evaluated_against_the_cloud(tmp_path, capsys, no_user_settings):
    from skelscope.compare_view import ab_rows

    y = shapes.y_shape(800, seed=5)
    files = write_shape_files(tmp_path, y)
    jittered = y.skeletal + np.random.default_rng(0).normal(0, 0.05, y.skeletal.shape)
    write_points_ply(tmp_path / "b_skeletal.ply", jittered)
    png = tmp_path / "ab.png"
    code = main([files["cloud"], "--skeletal", files["skeletal"], "--skeleton-b", str(tmp_path / "b_skeletal.ply"),
                 "--screenshot", str(png), "--quit"])
    captured = capsys.readouterr()
    assert code == 0, captured.err
    assert png.is_file() and "B-A" in captured.out
    expected = ab_rows(evaluate(y.cloud, y.skeletal).summary(), evaluate(y.cloud, jittered).summary())
    line = next(ln for ln in captured.out.splitlines() if ln.startswith("centeredness (skeletal)"))
    row = next(r for r in expected if r[0] == "centeredness (skeletal)")
    assert f"B-A {row[3]:+.4f}" in line and f"A {row[1]:10.4f}" in line
