"""Real screenshots of the SkelScope window into screenshots/ (``make screenshots`` runs this under Xvfb).

- ``window_empty.png``: the empty window and its hint.
- ``window_<metric>.png``: the bundled Y-shaped sample (cloud, skeletal points, curve skeleton)
  evaluated and coloured by each local metric; magenta marks invalid (NaN) values.
- ``barcode_panel.png``: the H0 barcode panel; ``histogram_panel.png``: the histogram panel.
- ``window_tubes.png``: edges as tubes, coloured by centeredness (the curve samples' values).
- ``figure_spheres.png``: File > Save picture at scale 2 with points as shaded spheres (points, lines
  and text grow with the scale); ``figure_eye_dome.png``: eye-dome lighting, no colour bar, no axes.
- ``window_skeletonized.png``: the skeletonizer's output for the sample cloud (issue 4), evaluated.
- ``window_hammer_skeletonized.png``: the real hammer scan (../shared/data, when present) skeletonized
  and evaluated, coloured by centeredness.
- ``error_dialog.png``: the dialog a corrupt file gives, over the window that survives it.

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


def main() -> int:
    from PySide6 import QtCore, QtWidgets

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(["skelscope-screenshots"])
    from app.main_window import MainWindow

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
    save(window, "window_empty.png")

    files = sample_files(tmp)
    window.session.load_files([files["cloud"], files["skeletal"], files["curve"]])
    wait_for_runner()
    if window.errors:
        print(f"error: {window.errors[0]}", file=sys.stderr)
        return 1
    window.view.standard_view("xy")
    for metric in ("boundedness", "centeredness", "smoothness"):
        window.scene.set_metric(metric)
        window.docks["Histogram" if metric == "centeredness" else "Barcodes"].raise_()
        if metric == "smoothness":
            # pick the junction of the Y (degree 3: smoothness NaN, drawn magenta)
            curve = window.scene.curve
            junction = int(curve.curve.degrees().argmax())
            x, y = window.view.world_to_display(curve.points[junction])
            window._picked(window.view.pick_display(x, y))
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

    window._picked(None)
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

    # Skeletonize the bare cloud (issue 4) and evaluate its output.
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

    # A real scan when the shared data folder is present (never copied into the repo).
    hammer = ROOT.parent / "shared" / "data" / "hammer_4096.ply"
    if hammer.is_file() and "skelcore.skeleton.pipeline" in sys.modules:
        window.session.load_as("cloud", str(hammer))
        window.session.start_skeletonize()
        wait_for_runner()
        wait_for_runner()
        window.scene.set_metric("centeredness")
        window.view.reset_camera()
        settle()
        save(window, "window_hammer_skeletonized.png")

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


if __name__ == "__main__":
    sys.path.insert(0, str(ROOT))
    os.environ.setdefault("QT_QPA_PLATFORM", "xcb")
    sys.exit(main())
