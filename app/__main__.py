"""``skelscope [CLOUD] [--skeletal F] [--curve F] [--metric NAME] [--screenshot OUT.png] [--camera F] [--quit]``

A thin main (silx's model): parse arguments, import Qt lazily, install an exception hook that shows
errors in a dialog, open the window. With ``--screenshot`` and ``--quit`` it loads, evaluates,
colours, saves the picture and exits: 0 on success, 2 on bad input (one line on stderr), 1 on a bug.
"""

from __future__ import annotations

import argparse
import os
import sys
import traceback
from typing import Any, Sequence

METRIC_CHOICES = ("boundedness", "centeredness", "smoothness")


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line on stderr, exit 2 (like skelcore's CLI)
        self.exit(2, f"skelscope: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    p = _Parser(prog="skelscope", description="See where a point-cloud skeleton is good or bad.")
    p.add_argument("cloud", nargs="?", help="the original point cloud")
    p.add_argument("--skeletal", metavar="F", help="skeletal point set in pointwise correspondence with the cloud")
    p.add_argument("--curve", metavar="F", help="curve skeleton (a file with edges)")
    p.add_argument("--metric", choices=METRIC_CHOICES, default="boundedness", help="local metric to colour by")
    p.add_argument("--screenshot", metavar="OUT.png", help="save the 3D view as PNG once evaluated")
    p.add_argument("--scale", type=int, default=1, help="screenshot scale factor (default 1)")
    p.add_argument("--transparent", action="store_true", help="screenshot with a transparent background")
    p.add_argument("--no-colour-bar", action="store_true", help="screenshot without the colour bar")
    p.add_argument("--camera", metavar="F", help="camera file written by View > Save camera (default: fit the data)")
    p.add_argument("--quit", action="store_true", help="exit after the screenshot (scripted use)")
    return p


def _fail(message: str, code: int = 2) -> int:
    print(f"skelscope: error: {' '.join(str(message).split())}", file=sys.stderr)
    return code


def _install_exception_hook(window: Any) -> None:
    """Uncaught exceptions in slots become a dialog (scripted: a recorded error), never a silent crash."""

    def hook(exc_type: type, exc: BaseException, tb: Any) -> None:
        text = "".join(traceback.format_exception(exc_type, exc, tb))
        sys.stderr.write(text)
        window.bug = text
        try:
            window.show_error("Unexpected error", f"{exc_type.__name__}: {exc}", text)
        except Exception:  # noqa: BLE001 - the hook itself must never raise
            pass

    sys.excepthook = hook


def _summary_lines(summary: dict[str, Any]) -> list[str]:
    from .panels.summary import COLUMNS, ROWS, summary_cells

    cells = summary_cells(summary)
    width = max(len(r) for r in ROWS)
    lines = [f"{'':{width}}  {COLUMNS[0]:>28}  {COLUMNS[1]:>28}"]
    lines += [f"{row:{width}}  {a:>28}  {b:>28}" for row, (a, b) in zip(ROWS, cells)]
    return lines


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    if args.scale < 1:
        return _fail("--scale must be a positive integer")
    if (args.skeletal or args.curve) and not args.cloud:
        return _fail("a skeletal point set or curve skeleton needs the cloud it was made from (CLOUD)")
    if args.quit and not args.screenshot and not args.cloud:
        return _fail("--quit without inputs has nothing to do")
    if args.screenshot and not os.path.isdir(os.path.dirname(os.path.abspath(args.screenshot))):
        return _fail(f"{args.screenshot}: output folder does not exist")
    camera = None
    if args.camera:
        from skelcore.errors import SkelInputError

        from .view.camera import load_camera

        try:
            camera = load_camera(args.camera)
        except SkelInputError as exc:
            return _fail(str(exc))
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")) \
            and os.environ.get("QT_QPA_PLATFORM", "") in ("", "xcb"):
        return _fail("no display: run under a desktop session or `xvfb-run -a skelscope ...`")

    import_view_libraries()
    from PySide6 import QtWidgets

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(["skelscope"])
    app.setApplicationName("SkelScope")
    app.setOrganizationName("SkelScope")
    from .main_window import MainWindow

    window = MainWindow()
    window.bug = None
    scripted = bool(args.quit)
    window.interactive = not scripted
    if scripted:  # the picture is of the 3D view only: give it the whole window
        for dock in window.docks.values():
            dock.hide()
    _install_exception_hook(window)
    window.show()
    app.processEvents()

    session = window.session
    with session.batch():
        for role, path in (("cloud", args.cloud), ("skeletal", args.skeletal), ("curve", args.curve)):
            if path and not session.load_as(role, path) and scripted:
                session.auto_evaluate = False
    window.scene.set_metric(args.metric)
    if camera is not None:
        window.view.set_camera_state(camera)
    if scripted and window.errors:
        return _fail(window.errors[0])
    if not args.screenshot and not scripted:
        return _exited(app.exec())

    _wait_for_runner(app, session)
    if window.errors:
        if scripted:
            return _fail(window.errors[0], 1 if window.bug else 2)
    if args.screenshot:
        app.processEvents()
        if camera is None:
            window.view.reset_camera()  # fit the final view size (docks may have moved since loading)
        else:
            window.view.set_camera_state(camera)
        try:
            path = window.save_screenshot(args.screenshot, scale=args.scale, transparent=args.transparent,
                                          colour_bar=not args.no_colour_bar)
        except (ValueError, OSError) as exc:
            if scripted:
                return _fail(str(exc))
            window.show_error("Screenshot failed", str(exc))
        else:
            print(f"skelscope: wrote {path}")
    if scripted:
        summary = window.scene.summary()
        if summary is not None:
            print("\n".join(_summary_lines(summary)))
        window.close()
        return 1 if window.bug else 0
    return _exited(app.exec())


def import_view_libraries() -> None:
    """The viewer's imports, in the order that starts it fastest (benchmarks/bench_app.py): numpy,
    VTK / pyvista (which loads matplotlib) and skelcore's readers before Qt, since once PySide6 is
    imported its import hook reads the source of every later module (PySide's ``__feature__`` check);
    and with the cyclic garbage collector paused, which would otherwise scan the ~300k objects the
    imports make again and again. Those objects are then frozen (left out of every later collection,
    which keeps collections short) and the collector runs again. Each saved ~0.4 s CPU at start-up."""
    import gc

    collecting = gc.isenabled()
    gc.disable()
    try:
        import numpy  # noqa: F401
        import pyvista.plotting  # noqa: F401

        import skelcore.io  # noqa: F401

        from PySide6 import QtWidgets  # noqa: F401

        from . import main_window  # noqa: F401
    finally:
        gc.freeze()
        if collecting:
            gc.enable()


def _exited(code: int) -> int:
    """The event loop has ended (the window closed, its task cancelled and waited for at most
    ``app.worker.SHUTDOWN_WAIT_S``). A task thread still inside an engine call without a checkpoint
    would only delay the exit: leave now, with the event loop's status."""
    from .worker import threads_alive

    if threads_alive():
        sys.stdout.flush()
        sys.stderr.flush()
        os._exit(code)
    return code


def _wait_for_runner(app: Any, session: Any) -> None:
    from PySide6 import QtCore

    if not session.runner.running:
        return
    loop = QtCore.QEventLoop()
    session.runner.finished.connect(loop.quit)
    if session.runner.running:
        loop.exec()
    app.processEvents()


if __name__ == "__main__":
    sys.exit(main())
