"""Real screenshots of the SkelScope window into screenshots/ (``make screenshots`` runs this under Xvfb).

- ``window_empty.png``: the empty window and its hint.
- ``window_<metric>.png``: the bundled Y-shaped sample (cloud, skeletal points, curve skeleton)
  evaluated and coloured by each local metric; magenta marks invalid (NaN) values.
- ``barcode_panel.png``: the H0 barcode panel; ``histogram_panel.png``: the histogram panel.
- ``window_tubes.png``: edges as tubes, coloured by centeredness (the curve samples' values).
- ``figure_spheres.png``: File > Save picture at scale 2 with points as shaded spheres (points, lines
  and text grow with the scale); ``figure_eye_dome.png``: eye-dome lighting, no colour bar, no axes;
  ``figure_black.png``: scale 2 on a black background (the colour bar's and the axes' text white).
- ``window_WxH.png`` (``--laptop``, run under a W x H screen; ``make screenshots`` does 1366 x 768 and
  1920 x 1080): the whole screen with the window filling it, the sample evaluated, an element picked
  and an evaluation running (status bar: stage, progress bar, Cancel). With ``QT_SCALE_FACTOR=1.5``
  (``--laptop`` again) it writes ``window_WxH_scale1.5.png``.
- ``window_skeletonized.png``: the skeletonizer's output for the sample cloud, evaluated.
- ``window_hammer_skeletonized.png``: the real hammer scan (resources/scans) skeletonized
  and evaluated, coloured by centeredness.
- ``error_dialog.png``: the dialog a corrupt file gives, over the window that survives it.
- Defects (``--defects`` makes only these; on the real hammer): ``window_defects.png``, the
  hammer with its cao curve cut to the middle of its handle (no head, no far end: pc-skeletor's truncated
  output), the Defects dock listing the two missing parts, the larger one selected (framed, its cloud points
  pink, highlighted in the pick colour); ``defects_panel.png``, the dock alone; ``window_branch.png``, a
  click on the curve: the branch's length, radius, metric means and flags in the pick panel.
- Openings: ``window_openings.png``, a one-sided scan of a cylinder (its front half) with its true axis: the
  opening's boundary loop drawn, the ``open_surface`` warning and the paper's boundedness near 0 (what
  Evaluate > Viewpoint… then corrects).
- Supports (``--supports`` makes only these): ``window_support_slab.png`` / ``support_slab_panel.png``
  (a curve sample's slab, ring and ellipse; ``support_slab_junction_panel.png`` near the junction), ``window_support_knn.png`` (a skeletal point's neighbours
  and centroids), ``support_directions_panel.png`` / ``support_paper_panel.png`` (direction map, paper
  triangles), ``window_filter.png`` (only the elements below beta*), ``window_ab.png`` (skeleton A
  against the skeletonizer's B: linked split view, A / B / B - A table), ``compare_run_dialog.png`` and
  ``window_ab_run.png`` (a ``skelcore compare`` run over the bundled samples, two of its report rows
  opened in the A/B view from the stored results; ``--ab-run`` makes only these two).

Falls back to freshly generated shapes in a temporary folder when resources/samples/ is missing.
"""

from __future__ import annotations

import os
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "screenshots"


def sample_files(tmp: Path) -> dict[str, str]:
    samples = ROOT / "resources" / "samples"
    names = {k: samples / f"yshape_{k}.ply" for k in ("cloud", "skeletal", "curve")}
    if all(p.is_file() for p in names.values()):
        return {k: str(v) for k, v in names.items()}
    from skelcore import shapes
    from skelcore.io import write_curve_ply, write_points_ply

    sh = shapes.y_shape(4096, seed=0)
    names = {k: tmp / f"yshape_{k}.ply" for k in ("cloud", "skeletal", "curve")}
    write_points_ply(names["cloud"], sh.cloud)
    write_points_ply(names["skeletal"], sh.skeletal)
    write_curve_ply(names["curve"], sh.curve_vertices, sh.curve_edges)
    return {k: str(v) for k, v in names.items()}


def laptop_screenshot() -> int:
    """The window on the whole screen (1366 x 768, 1920 x 1080), filling it as a maximized window would."""
    from PySide6 import QtCore, QtWidgets

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(["skelscope-screenshots"])
    from skelscope.main_window import MainWindow

    OUT.mkdir(exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix="skelscope-shots-"))
    window = MainWindow(settings=QtCore.QSettings(str(tmp / "settings.ini"), QtCore.QSettings.Format.IniFormat))
    window.session.ask = lambda question, options: options[0]
    screen = window.screen()
    window.setGeometry(screen.availableGeometry())
    window.show()

    def settle(ms: int = 400) -> None:
        loop = QtCore.QEventLoop()
        QtCore.QTimer.singleShot(ms, loop.quit)
        loop.exec()

    settle(800)
    files = sample_files(tmp)
    window.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    while window.session.runner.running:
        settle(200)
    window.scene.set_metric("centeredness")
    window.view.standard_view("xy")
    curve = window.scene.curve
    junction = int(curve.curve.degrees().argmax())
    window.select_element("curve", "vertices", junction)
    settle(1500)
    window.session.start_evaluation()  # a run in progress: the status bar's stage, progress and Cancel
    settle(250)
    scale = os.environ.get("QT_SCALE_FACTOR", "1")
    shot = QtWidgets.QApplication.primaryScreen().grabWindow(0)  # the whole screen, in device pixels
    size = f"{shot.width()}x{shot.height()}"
    name = f"window_{size}.png" if scale in ("", "1") else f"window_{size}_scale{scale}.png"
    shot.save(str(OUT / name))
    print(f"wrote screenshots/{name} (screen {screen.size().width()} x {screen.size().height()} at scale {scale})")
    window.session.runner.shutdown()
    window.close()
    return 0


def main() -> int:
    from PySide6 import QtCore, QtWidgets

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(["skelscope-screenshots"])
    from skelscope.main_window import MainWindow

    OUT.mkdir(exist_ok=True)
    tmp = Path(tempfile.mkdtemp(prefix="skelscope-shots-"))
    settings = QtCore.QSettings(str(tmp / "settings.ini"), QtCore.QSettings.Format.IniFormat)
    window = MainWindow(settings=settings)
    window.session.ask = lambda question, options: options[0]  # every question's default (no dialogs)
    window.resize(1600, 960)
    window.show()
    app.processEvents()

    def settle(ms: int = 300) -> None:
        loop = QtCore.QEventLoop()
        QtCore.QTimer.singleShot(ms, loop.quit)
        loop.exec()
        window.view.plotter.render()
        app.processEvents()

    def wait_for_runner() -> None:
        if window.session.runner.running:
            loop = QtCore.QEventLoop()
            window.session.runner.finished.connect(loop.quit)
            loop.exec()
        settle()

    def save(widget: QtWidgets.QWidget, name: str) -> None:
        path = OUT / name
        widget.grab().save(str(path))
        print(f"wrote {path.relative_to(ROOT)}")

    settle(600)
    if "--defects" in sys.argv:
        defects_screenshots(window, settle, save, wait_for_runner, tmp)
        window.session.runner.shutdown()
        window.close()
        return 0
    save(window, "window_empty.png")

    files = sample_files(tmp)
    window.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    wait_for_runner()
    if window.errors:
        print(f"error: {window.errors[0]}", file=sys.stderr)
        return 1
    window.view.standard_view("xy")
    if "--ab-run" not in sys.argv:
        support_screenshots(window, settle, save)
    ab_run_screenshots(window, settle, save, tmp)
    if "--supports" in sys.argv or "--ab-run" in sys.argv:
        window.session.runner.shutdown()
        window.close()
        return 0
    for metric in ("boundedness", "centeredness", "smoothness"):
        window.scene.set_metric(metric)
        window.docks["Histogram" if metric == "centeredness" else "Barcodes"].raise_()
        if metric == "smoothness":
            # pick the junction of the Y (degree 3: smoothness NaN, drawn magenta)
            curve = window.scene.curve
            junction = int(curve.curve.degrees().argmax())
            x, y = window.view.world_to_display(curve.points[junction])
            info = window.view.pick_display(x, y)  # the pick panel only: no support overlay in this picture
            window.pick.show_info(info)
            window.show_message(f"{info['element']} #{info['index']}", 5000)
        settle()
        save(window, f"window_{metric}.png")
    window.docks["Barcodes"].raise_()
    settle()
    save(window.docks["Barcodes"], "barcode_panel.png")
    window.docks["Histogram"].raise_()
    window.scene.set_metric("boundedness")
    settle()
    save(window.docks["Histogram"], "histogram_panel.png")
    window.docks["Barcodes"].raise_()

    window.pick_element(None)
    window.view._remove_marker()
    window.scene.set_metric("centeredness")
    window.actions_by_name["tubes"].trigger()  # the T key's action: the checkbox follows
    settle()
    save(window, "window_tubes.png")
    window.actions_by_name["tubes"].trigger()
    window.view.standard_view("iso")
    window.scene.set_style("spheres", True)
    window.scene.set_metric("centeredness")
    settle()
    window.save_screenshot(str(OUT / "figure_spheres.png"), scale=2)
    print("wrote screenshots/figure_spheres.png")
    window.scene.set_style("spheres", False)
    window.scene.set_style("eye_dome", True)
    window.scene.set_style("axes", False)
    settle()
    window.save_screenshot(str(OUT / "figure_eye_dome.png"), scale=2, colour_bar=False)
    print("wrote screenshots/figure_eye_dome.png")
    window.scene.set_style("eye_dome", False)
    window.scene.set_style("axes", True)
    window.scene.set_metric("smoothness")  # NaN at the junction and tips: the NaN legend too
    settle()
    window.save_screenshot(str(OUT / "figure_black.png"), scale=2, background="black")
    print("wrote screenshots/figure_black.png")

    # Skeletonize the bare cloud and evaluate its output.
    try:
        import skelcore.skeleton.pipeline  # noqa: F401
    except ImportError:
        pass
    else:
        window.session.load_as("cloud", files["cloud"])  # a new cloud clears the old skeleton (the default)
        window.session.start_skeletonize()
        wait_for_runner()
        wait_for_runner()  # the evaluation that follows
        window.scene.set_metric("centeredness")
        window.view.standard_view("xy")
        settle()
        save(window, "window_skeletonized.png")

    # A real scan (resources/scans).
    hammer = ROOT / "resources" / "scans" / "hammer_4096.ply"
    if "skelcore.skeleton.pipeline" in sys.modules:
        window.session.load_as("cloud", str(hammer))
        window.session.start_skeletonize()
        wait_for_runner()
        wait_for_runner()
        window.scene.set_metric("centeredness")
        window.view.reset_camera()
        settle()
        save(window, "window_hammer_skeletonized.png")

    defects_screenshots(window, settle, save, wait_for_runner, tmp)

    # A corrupt file: the dialog, grabbed while it is open, then closed.
    bad = tmp / "broken_cloud.ply"
    bad.write_bytes(Path(files["cloud"]).read_bytes()[:400])

    def grab_dialog() -> None:
        box = QtWidgets.QApplication.activeModalWidget()
        if box is None:
            QtCore.QTimer.singleShot(200, grab_dialog)
            return
        app.processEvents()
        screen = QtWidgets.QApplication.primaryScreen().grabWindow(0)
        geo = window.frameGeometry().united(box.frameGeometry())
        screen.copy(geo).save(str(OUT / "error_dialog.png"))
        print(f"wrote {(OUT / 'error_dialog.png').relative_to(ROOT)}")
        box.close()

    QtCore.QTimer.singleShot(500, grab_dialog)
    window.session.load_as("skeletal", str(bad))
    window.session.runner.shutdown()
    window.close()
    return 0


def defects_screenshots(window, settle, save, wait_for_runner, tmp: Path) -> None:
    """The Defects dock on the truncated cao hammer; the openings on a one-sided cylinder."""
    import numpy as np

    from skelcore import shapes
    from skelcore.curve import CurveSkeleton
    from skelcore.io import load_cloud, write_curve_ply, write_points_ply

    hammer = ROOT / "resources" / "scans" / "hammer_4096.ply"
    try:
        from skelcore.skeleton import skeletonize
    except ImportError:
        skeletonize = None
    if skeletonize is not None:
        _skeletal, curve = skeletonize(load_cloud(hammer), method="cao")
        y = curve.vertices[:, 1]  # the handle runs along y from -199 to about 80, the head beyond
        keep = (y > -60) & (y < 85)
        new = -np.ones(len(keep), np.int64)
        new[keep] = np.arange(int(keep.sum()))
        cut = CurveSkeleton.from_raw(curve.vertices[keep], new[curve.edges[keep[curve.edges].all(axis=1)]])
        path = tmp / "hammer_cao_half_handle_curve.ply"
        write_curve_ply(path, cut.vertices, cut.edges)
        window.session.close_all()  # nothing of the earlier shots stays (a skeletal set would be kept)
        window.session.load_files([str(hammer), str(path)])
        wait_for_runner()
        window.scene.set_metric("centeredness")
        window.docks["Defects"].raise_()
        window.view.standard_view("xy")
        settle()
        rows = window.defects.rows
        biggest = max(range(len(rows)), key=lambda i: len(rows[i].cloud_rows)) if rows else -1
        window.defects.panel.select_row(biggest)
        settle(800)
        save(window, "window_defects.png")
        save(window.docks["Defects"], "defects_panel.png")
        window.view.standard_view("xy")
        settle()
        tip = cut.vertices[int(np.argmax(cut.vertices[:, 1]))]
        x, y = window.view.world_to_display(tip)
        window.pick_element(window.view.pick_display(x, y))
        settle(800)
        save(window, "window_branch.png")
        window.pick_element(None)
    s = shapes.cylinder(n=4000, seed=1)
    front = s.cloud[s.cloud[:, 1] > 0]
    write_points_ply(tmp / "cylinder_front_cloud.ply", front)
    write_curve_ply(tmp / "cylinder_axis_curve.ply", s.curve_vertices, s.curve_edges)
    window.session.close_all()
    window.session.load_files([str(tmp / "cylinder_front_cloud.ply"), str(tmp / "cylinder_axis_curve.ply")])
    wait_for_runner()
    window.scene.set_metric("boundedness")
    window.docks["Defects"].raise_()
    window.view.standard_view("iso")
    settle(800)
    save(window, "window_openings.png")
    window.docks["Barcodes"].raise_()


def support_screenshots(window, settle, save) -> None:
    """Each metric's local support on screen, for elements on the Y's upper arm."""
    import numpy as np

    import skelcore

    scene, sup = window.scene, window.supports
    ev = scene.evaluation
    samples = ev.curve.samples
    mid = int(np.argsort(np.abs(samples[:, 1] - 0.5 * (samples[:, 1].max() + np.median(samples[:, 1]))))[0])
    scene.set_metric("centeredness")
    info = scene.element_info("curve", "samples", mid)
    window.view._show_marker(info["xyz"])
    window.pick_element(info)
    settle(500)
    save(window, "window_support_slab.png")
    save(window.docks["Support"], "support_slab_panel.png")
    # near the junction the slab also cuts the other arms: the ring keeps the nearest cross-section only
    upper = np.flatnonzero((np.abs(samples[:, 0] - samples[mid, 0]) < 0.02) & (samples[:, 1] > 0))
    near = int(upper[np.argmin(np.abs(samples[upper, 1] - 0.12))])
    window.pick_element(scene.element_info("curve", "samples", near))
    settle(500)
    save(window.docks["Support"], "support_slab_junction_panel.png")
    skel = scene.skeletal.points
    k = int(np.argmin(np.linalg.norm(skel - samples[mid], axis=1)))
    info = scene.element_info("skeletal", "points", k)
    window.view._show_marker(info["xyz"])
    window.pick_element(info)
    settle(500)
    save(window, "window_support_knn.png")
    scene.set_metric("boundedness")  # the same element's direction map
    settle(500)
    save(window.docks["Support"], "support_directions_panel.png")
    # the paper estimator on a few skeletal points (its triangulation per query is slow)
    params = ev.params.replace(boundedness_method="paper")
    few = skel[::64]
    ev_paper = skelcore.evaluate(ev.cloud, few, params=params)
    window.session.show_arrays(ev.cloud, few, scene.curve.curve, None)
    window.session.runner.discard()
    scene.set_evaluation(ev_paper)
    scene.set_metric("boundedness")
    info = scene.element_info("skeletal", "points", int(np.argmin(np.linalg.norm(few - skel[k], axis=1))))
    window.pick_element(info)
    settle(500)
    save(window.docks["Support"], "support_paper_panel.png")
    window.session.show_arrays(ev.cloud, skel, scene.curve.curve, ev)
    scene.set_metric("boundedness")
    window.pick_element(None)
    window.view._remove_marker()
    beta_star = scene.beta_star
    scene.set_thresholds(0.9, scene.c_star)  # a stricter beta*: the arms' ends fall below it
    window.summary.set_thresholds(scene.beta_star, scene.c_star)
    sup.set_filter(True)
    settle(500)
    save(window, "window_filter.png")
    sup.set_filter(False)
    scene.set_thresholds(beta_star, scene.c_star)
    window.summary.set_thresholds(scene.beta_star, scene.c_star)
    settle()
    ab_screenshot(window, settle)


def ab_screenshot(window, settle) -> None:
    """The bundled skeleton (A) against the skeletonizer's (B) of the same cloud, ``window_ab.png``."""
    from PySide6 import QtCore

    try:
        from skelcore.skeleton import skeletonize
    except ImportError:
        return
    ev = window.scene.evaluation
    skeletal, curve = skeletonize(ev.cloud)
    window.compare.compare_arrays(skeletal, curve, "skeletonized (Cao et al.)")
    while window.session.runner.running:
        loop = QtCore.QEventLoop()
        QtCore.QTimer.singleShot(200, loop.quit)
        loop.exec()
    settle()
    view = window.compare.views[-1]
    view.resize(1400, 850)
    view.metric_box.setCurrentText("centeredness")
    view.plotter.view_xy()
    settle(800)
    view.grab().save(str(OUT / "window_ab.png"))
    print("wrote screenshots/window_ab.png")
    view.close()


AB_RUN_MANIFEST = """
[[shapes]]
path = "{samples}/*_cloud.ply"
suffix = "_cloud"
[[methods]]
name = "truth"
kind = "files"
skeletal = "{samples}/{{stem}}_skeletal.ply"
curve = "{samples}/{{stem}}_curve.ply"
[[methods]]
name = "lbc_files"
kind = "files"
skeletal = "{samples}/{{stem}}_lbc_skeletal.ply"
curve = "{samples}/{{stem}}_lbc_curve.ply"
[[methods]]
name = "cao"
kind = "builtin"
[[conditions]]
name = "normal"
[[conditions]]
name = "noise"
noise = 0.05
"""


def ab_run_screenshots(window, settle, save, tmp: Path) -> None:
    """A ``skelcore compare`` run over the bundled samples (true skeletons, the stored LBC
    output, the built-in skeletonizer), its dialog and two report rows in the A/B view, stored results."""
    samples = ROOT / "resources" / "samples"
    if not (samples / "yshape_lbc_skeletal.ply").is_file():
        return
    from skelcore.compare import Backend, run_compare

    (tmp / "run.toml").write_text(AB_RUN_MANIFEST.format(samples=samples.as_posix()))
    out = tmp / "compare_run"
    run_compare(tmp / "run.toml", out, Backend("serial"), report=False)
    dialog = window.compare_run.open(out)
    dialog.select(dataset="yshape", condition="normal", a="truth", b="cao")
    dialog.table.selectRow(2)
    settle()
    save(dialog, "compare_run_dialog.png")
    view = dialog.open_ab()
    view.resize(1400, 850)
    view.metric_box.setCurrentText("centeredness")
    view.plotter.view_xy()
    settle(800)
    save(view, "window_ab_run.png")
    view.close()
    dialog.close()


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    os.environ.setdefault("QT_QPA_PLATFORM", "xcb")
    sys.exit(laptop_screenshot() if "--laptop" in sys.argv else main())
