"""``skelscope [CLOUD] [--skeletal F] [--curve F [--edits LOG.json]] [--session F] [--metric NAME] [--screenshot OUT.png] [--camera F]
[--size W H] [--background white|black|transparent] [--quit]`` (and the A/B view: ``--skeleton-b F``, or
``--compare-run DIR --a METHOD --b METHOD [--dataset NAME]``)

A thin main (silx's model): parse arguments, import Qt lazily, install an exception hook that shows
errors in a dialog, open the window. Loading the inputs and the scripted mode (``--screenshot`` and
``--quit``: evaluate, colour, save the picture, exit 0 on success, 2 on bad input with one line on
stderr, 1 on a bug) live in :mod:`skelscope.scripted`.
"""

from __future__ import annotations

import argparse
import os
import sys
import traceback
from types import TracebackType
from typing import TYPE_CHECKING, NoReturn, Sequence

from .scripted import check_arguments, fail, run
from skelcore.scores import LOCAL_METRICS

if TYPE_CHECKING:
    from .window_api import WindowApi

METRIC_CHOICES = LOCAL_METRICS


class _Parser(argparse.ArgumentParser):
    def error(self, message: str) -> None:  # one line on stderr, exit 2 (like skelcore's CLI)
        self.exit(2, f"skelscope: error: {message}\n")


def build_parser() -> argparse.ArgumentParser:
    # no prefix matching: "--skeleton" must not silently mean "--skeleton-b" (the A/B view)
    p = _Parser(prog="skelscope", description="See where a point-cloud skeleton is good or bad.", allow_abbrev=False)
    p.add_argument("cloud", nargs="?", help="the original point cloud")
    p.add_argument("--skeletal", metavar="F", help="skeletal point set in pointwise correspondence with the cloud")
    p.add_argument("--curve", metavar="F", help="curve skeleton (a file with edges)")
    p.add_argument("--session", metavar="F", help="a session saved by File > Save session (files, settings, "
                   "display, camera, picked element); instead of CLOUD, --skeletal, --curve")
    p.add_argument("--edits", metavar="LOG.json", help="an edit log (Save skeleton as…'s NAME.edits.json, "
                   "skelcore edit's --ops) replayed on --curve before it is scored, as undoable edits; a log made "
                   "for another skeleton is refused")
    p.add_argument("--metric", choices=METRIC_CHOICES, default=None,
                   help="local metric to colour by (default: the session's, else boundedness)")
    p.add_argument("--screenshot", metavar="OUT.png", help="save the 3D view as PNG once evaluated")
    p.add_argument("--scale", type=int, default=1, help="screenshot scale factor (default 1)")
    p.add_argument("--background", choices=("white", "black", "transparent"), default=None,
                   help="screenshot background (default white; black turns the text white)")
    p.add_argument("--transparent", action="store_true", help="same as --background transparent")
    p.add_argument("--no-colour-bar", action="store_true", help="screenshot without the colour bar")
    p.add_argument("--camera", metavar="F", help="camera file written by View > Save camera (default: fit the data, "
                   "or the session's camera)")
    p.add_argument("--size", metavar=("W", "H"), type=int, nargs=2,
                   help="the 3D view's size in pixels at scale 1 (default: the camera file's or session's view "
                   "size, which reproduces its framing; else the window's)")
    p.add_argument("--quit", action="store_true", help="exit after the screenshot (scripted use)")
    ab = p.add_argument_group("two skeletons side by side (A/B view; --screenshot then saves that window)")
    ab.add_argument("--skeleton-b", metavar="F", action="append", default=[],
                    help="skeleton B (skeletal set or curve; twice for both), evaluated against CLOUD like A")
    ab.add_argument("--compare-run", metavar="DIR", help="a skelcore compare output folder: open two of its "
                    "methods' stored results (with --a, --b, optionally --dataset, --condition, --seed)")
    ab.add_argument("--dataset", metavar="NAME", help="the run's dataset (shape; default: its first)")
    ab.add_argument("--condition", metavar="NAME", help="the run's condition (default: its first)")
    ab.add_argument("--seed", metavar="N", type=int, help="the run's seed (default: its first)")
    ab.add_argument("--a", metavar="METHOD", help="the run's method shown as A")
    ab.add_argument("--b", metavar="METHOD", help="the run's method shown as B")
    return p


def _install_exception_hook(window: WindowApi) -> None:
    """Uncaught exceptions in slots become a dialog (scripted: a recorded error, exit 1), never a silent crash."""

    def hook(exc_type: type[BaseException], exc: BaseException, tb: TracebackType | None) -> None:
        text = "".join(traceback.format_exception(exc_type, exc, tb))
        sys.stderr.write(text)
        try:
            window.report_bug(f"{exc_type.__name__}: {exc}", text)
        except Exception:  # noqa: BLE001 - the hook itself must never raise
            pass

    sys.excepthook = hook


# The ``app`` extra: without one of these the viewer cannot start (the engine, ``skelcore``, needs none).
VIEWER_LIBRARIES = ("PySide6", "pyvista", "pyvistaqt", "matplotlib")


def missing_viewer_libraries() -> list[str]:
    """The viewer's libraries that are not installed (none with ``pip install 'skelscope[app]'``)."""
    import importlib.util

    return [name for name in VIEWER_LIBRARIES if importlib.util.find_spec(name) is None]


def main(argv: Sequence[str] | None = None) -> int:
    args = build_parser().parse_args(argv)
    missing = missing_viewer_libraries()
    if missing:
        return fail(f"the viewer needs {', '.join(missing)}, not installed: pip install 'skelscope[app]'")
    try:
        startup = check_arguments(args)
    except ValueError as exc:  # SkelInputError included: one line, exit 2, before any window
        return fail(str(exc))
    if sys.platform.startswith("linux") and not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")) \
            and os.environ.get("QT_QPA_PLATFORM", "") in ("", "xcb"):
        return fail("no display: run under a desktop session or `xvfb-run -a skelscope ...`")

    import_view_libraries()
    from PySide6 import QtWidgets

    app = QtWidgets.QApplication.instance() or QtWidgets.QApplication(["skelscope"])
    app.setApplicationName("SkelScope")
    app.setOrganizationName("SkelScope")
    from .main_window import MainWindow

    window = MainWindow()
    _install_exception_hook(window)
    code = run(app, window, startup)
    if code is None:
        return _exited(app.exec())
    window.close()  # a scripted run's end, an error's too: the window and its hold on the collector go
    return code


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


def _exited(code: int) -> NoReturn:
    """The event loop has ended (the window closed, its tasks cancelled and detached, never waited
    for, its settings synced): leave now, with the event loop's status.

    Not through the interpreter's teardown: freeing a million-point scene, VTK's objects and every
    module took 0.4-0.9 s after the window had closed (Ctrl+Q should take 0.5 s), and a task thread
    still inside an engine call would delay it further. Nothing is left to save by then."""
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


if __name__ == "__main__":
    sys.exit(main())
