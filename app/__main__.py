"""``skelscope [CLOUD] [--skeletal F] [--curve F] [--metric NAME] [--screenshot OUT.png] [--camera F] [--quit]``
(and the A/B view: ``--skeleton-b F``, or ``--compare-run DIR --a METHOD --b METHOD [--dataset NAME]``)

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
    # no prefix matching: "--skeleton" must not silently mean "--skeleton-b" (the A/B view)
    p = _Parser(prog="skelscope", description="See where a point-cloud skeleton is good or bad.", allow_abbrev=False)
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
    if args.quit and not args.screenshot and not args.cloud and not args.compare_run:
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
    try:
        ab = _ab_inputs(args)
    except ValueError as exc:  # SkelInputError included: one line, exit 2, before any window
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
    _start_ab(window, ab)
    if not args.screenshot and not scripted:
        return _exited(app.exec())

    _wait_for_runner(app, session)
    if ab is not None and ab[0] == "b":
        app.processEvents()  # B starts once A's evaluation has landed
        _wait_for_runner(app, session)
    if window.errors:
        if scripted:
            return _fail(window.errors[0], 1 if window.bug else 2)
    if args.screenshot and ab is not None:
        code = _save_ab_picture(app, window, args.screenshot, scripted)
        if code:
            return code
    elif args.screenshot:
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
        for view in window.compare.views[-1:] if ab is not None else []:
            cells = [[view.cell(r, c) for c in range(4)] for r in range(len(view.rows))]
            print("\n".join(f"{label:24} A {a:>10}  B {b:>10}  B-A {d}" for label, a, b, d in cells))
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


def _ab_inputs(args: argparse.Namespace) -> tuple[str, Any] | None:
    """The A/B view's inputs, checked before any window opens: ("run", (jobs, evaluations, run)) for
    --compare-run (stored results read now, nothing recomputed), ("b", (skeletal, curve, name)) for
    --skeleton-b. Raises ValueError / SkelInputError with one line."""
    run_opts = [o for o, v in (("--dataset", args.dataset), ("--condition", args.condition), ("--seed", args.seed),
                               ("--a", args.a), ("--b", args.b)) if v is not None]
    if args.compare_run:
        if args.cloud or args.skeletal or args.curve or args.skeleton_b:
            raise ValueError("--compare-run opens a run's stored results: give no CLOUD, --skeletal, --curve "
                             "or --skeleton-b with it")
        if args.a is None or args.b is None:
            raise ValueError("--compare-run needs --a METHOD and --b METHOD")
        from skelcore.compare.finished_run import open_run

        from .compare_run import load_ab

        run = open_run(args.compare_run)
        return "run", (*load_ab(run, args.dataset, args.a, args.b, args.condition, args.seed), run)
    if run_opts:
        raise ValueError(f"{run_opts[0]} goes with --compare-run DIR")
    if not args.skeleton_b:
        return None
    if not args.cloud or not (args.skeletal or args.curve):
        raise ValueError("--skeleton-b needs CLOUD and skeleton A (--skeletal and/or --curve)")
    from skelcore.io import load_any

    got: dict[str, Any] = {}
    for path in args.skeleton_b:
        item = load_any(path)
        kind = "curve" if item.kind == "curve" else "skeletal"
        if kind in got:
            raise ValueError(f"--skeleton-b: two {kind} files ({got[kind][0]}, {path}); give one skeletal set "
                             "and/or one curve")
        got[kind] = (path, item.curve if kind == "curve" else item.points)
    skeletal, curve = (got[k][1] if k in got else None for k in ("skeletal", "curve"))
    return "b", (skeletal, curve, ", ".join(os.path.basename(p) for p in args.skeleton_b))


def _start_ab(window: Any, ab: tuple[str, Any] | None) -> None:
    """--compare-run: A's stored result in the main window and the A/B view at once; --skeleton-b:
    B is evaluated in the worker once A's evaluation has landed, then the A/B view opens."""
    if ab is None:
        return
    from PySide6 import QtCore

    kind, data = ab
    if kind == "run":
        from .compare_run import ab_context

        job_a, job_b, ev_a, ev_b, run = data
        window.open_variant(ev_a.cloud, None if ev_a.skeletal is None else ev_a.skeletal.points,
                            None if ev_a.curve is None else ev_a.curve.curve, ev_a)
        window.compare.open(ev_a, ev_b, (job_a.method, job_b.method), thresholds=None,
                            context=ab_context(run, job_a))
        return
    skeletal, curve, name = data

    def start_b(_ev: Any = None) -> None:
        window.session.evaluated.disconnect(start_b)
        QtCore.QTimer.singleShot(0, lambda: window.compare.compare_arrays(skeletal, curve, name))

    window.session.evaluated.connect(start_b)


def _save_ab_picture(app: Any, window: Any, path: str, scripted: bool) -> int:
    """The A/B window (split view and table) as PNG; 0, or the exit status of a failure."""
    from .exports import write_png

    views = [v for v in window.compare.views if v.isVisible()]
    if not views:
        return _fail("the A/B view did not open", 1 if window.bug else 2) if scripted else 0
    app.processEvents()
    try:
        out = write_png(path, views[-1].picture(), window._inputs())
    except (ValueError, OSError) as exc:
        if scripted:
            return _fail(str(exc))
        window.show_error("Screenshot failed", str(exc))
        return 0
    print(f"skelscope: wrote {out}")
    return 0


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
