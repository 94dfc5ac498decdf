"""The viewer started with inputs from the command line, and its scripted mode (``--screenshot``, ``--quit``).

:func:`check_arguments` reads every input the options name (camera file, saved session, a compare
run's stored results, skeleton B, edit log) before any window opens, so bad input is one line and exit 2.
:func:`run` sizes the 3D view (``--size W H``, else for ``--screenshot`` the camera's or session's saved view size,
so a saved camera frames the data as it did; a window for the user keeps fitting the screen), loads the inputs
(with ``--edits``, the edit log replayed on the curve before it is scored) or restores the session into the window,
starts the A/B view (``--skeleton-b``, ``--compare-run``), waits for the evaluation, saves the picture
(``--scale``, ``--background``) and prints the scores; scripted (``--quit``) it closes the window and
returns the exit status: 0 on success, 2 on bad input, 1 on a bug (an uncaught exception). It uses the
window through :class:`skelscope.window_api.WindowApi` only.
"""

from __future__ import annotations

import argparse
import os
import sys
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

if TYPE_CHECKING:  # Qt is imported after the view libraries (app.__main__.import_view_libraries)
    from PySide6 import QtWidgets

    from .session import Session
    from .window_api import WindowApi

__all__ = ["Startup", "check_arguments", "fail", "run", "fit_view_size"]


def fail(message: str, code: int = 2) -> int:
    """One line on stderr (like skelcore's CLI); returns ``code``, the exit status."""
    print(f"skelscope: error: {' '.join(str(message).split())}", file=sys.stderr)
    return code


@dataclass(frozen=True)
class Startup:
    """The command line with its inputs read: the options, the camera, the A/B view's inputs."""

    args: argparse.Namespace
    camera: dict[str, Any] | None
    ab: tuple[str, Any] | None
    session: Any = None  # app.session_file.SessionState of --session
    view_size: tuple[int, int] | None = None  # --size, else (--screenshot) the camera's or the session's saved one
    edits: dict[str, Any] | None = None  # --edits: the edit log, checked against --curve

    @property
    def scripted(self) -> bool:
        return bool(self.args.quit)

    @property
    def background(self) -> str:
        return "transparent" if self.args.transparent else (self.args.background or "white")


def check_arguments(args: argparse.Namespace) -> Startup:
    """The options checked and their files read before any window opens; ValueError (SkelInputError
    included) with one line on bad input."""
    from .view.camera import MAX_VIEW_SIZE

    if args.scale < 1:
        raise ValueError("--scale must be a positive integer")
    if args.transparent and args.background not in (None, "transparent"):
        raise ValueError(f"--transparent contradicts --background {args.background}")
    if args.size is not None and not all(1 <= v <= MAX_VIEW_SIZE for v in args.size):
        raise ValueError(f"--size W H must be two integers in 1..{MAX_VIEW_SIZE}")
    if args.session and (args.cloud or args.skeletal or args.curve or args.compare_run or args.skeleton_b):
        raise ValueError("--session names its own files: give no CLOUD, --skeletal, --curve, --skeleton-b or "
                         "--compare-run with it")
    if (args.skeletal or args.curve) and not args.cloud:
        raise ValueError("a skeletal point set or curve skeleton needs the cloud it was made from (CLOUD)")
    if args.quit and not args.screenshot and not args.cloud and not args.compare_run and not args.session:
        raise ValueError("--quit without inputs has nothing to do")
    if args.screenshot and not os.path.isdir(os.path.dirname(os.path.abspath(args.screenshot))):
        raise ValueError(f"{args.screenshot}: output folder does not exist")
    camera = None
    if args.camera:
        from .view.camera import load_camera

        camera = load_camera(args.camera)
    session = None
    if args.session:
        from .session_file import read_session

        session = read_session(args.session)
    saved = camera if camera is not None else (session.camera if session is not None else None)
    # a saved view size frames a --screenshot as it was framed; a window for the user fits their screen
    view_size = tuple(args.size) if args.size else (tuple(saved["view_size"]) if args.screenshot and saved
                                                     and saved.get("view_size") else None)
    return Startup(args, camera, _ab_inputs(args), session, view_size, _edit_log(args))


def _edit_log(args: argparse.Namespace) -> dict[str, Any] | None:
    """--edits read and replayed once on --curve: a log that is not one, made for another skeleton or
    with an operation that does not apply is one line naming the log (SkelInputError)."""
    if not args.edits:
        return None
    if not args.curve:
        raise ValueError("--edits LOG.json goes with --curve C, the curve skeleton it was made for")
    import skelcore.edit as edit
    from skelcore.errors import SkelInputError
    from skelcore.io import load_curve

    log = edit.read_log(args.edits)
    try:
        edit.replay(load_curve(args.curve), log)
    except SkelInputError as exc:
        if exc.path is not None:  # the curve's own file
            raise
        raise SkelInputError(f"{exc} (--curve {args.curve})", args.edits) from None
    return log


def run(app: QtWidgets.QApplication, window: WindowApi, startup: Startup) -> int | None:
    """Load, colour, start the A/B view; with ``--screenshot`` wait and save the picture. Returns the
    exit status when scripted (or on a failure), None when the event loop should run."""
    args, camera, ab, scripted = startup.args, startup.camera, startup.ab, startup.scripted
    window.interactive = not scripted
    if scripted:  # the picture is of the 3D view only: give it the whole window
        for dock in window.docks.values():
            dock.hide()
    window.widget.show()
    app.processEvents()
    if startup.view_size is not None:
        try:
            fit_view_size(app, window, startup.view_size)
        except ValueError as exc:
            if scripted:
                return fail(str(exc))
            window.show_error("View size", str(exc))

    session = window.session
    if startup.session is not None:
        problems = window.saved_sessions.restore(startup.session, args.session)
        window.saved_sessions.report(problems, os.path.basename(args.session))
        if scripted and not window.scene.layers:
            return fail(problems[0] if problems else f"{args.session}: the session names no file")
        if camera is None:
            camera = startup.session.camera
    else:
        with session.batch():
            for role, path in (("cloud", args.cloud), ("skeletal", args.skeletal), ("curve", args.curve)):
                if path and not session.load_as(role, path) and scripted:
                    session.auto_evaluate = False
            if startup.edits is not None and window.scene.curve is not None:  # scored once, edited
                problems = window.replay_curve_edits(startup.edits)
                if problems:
                    if scripted:  # no picture of the curve unedited
                        session.auto_evaluate = False
                    window.show_error("Edit log", problems[0])
                elif scripted:
                    print(f"skelscope: replayed {len(startup.edits['operations'])} edit(s) of "
                          f"{os.path.basename(args.edits)} on {os.path.basename(args.curve)}")
    if args.metric:
        window.scene.set_metric(args.metric)
    if camera is not None:
        window.view.set_camera_state(camera)
    if scripted and window.errors:
        return fail(window.errors[0])
    _start_ab(window, ab)
    if not args.screenshot and not scripted:
        return None

    _wait_for_runner(app, session)
    if ab is not None and ab[0] == "b":
        app.processEvents()  # B starts once A's evaluation has landed
        _wait_for_runner(app, session)
    if window.errors:
        if scripted:
            return fail(window.errors[0], 1 if window.bug else 2)
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
            path = window.save_screenshot(args.screenshot, scale=args.scale, colour_bar=not args.no_colour_bar,
                                          background=startup.background)
        except (ValueError, OSError) as exc:
            if scripted:
                return fail(str(exc))
            window.show_error("Screenshot failed", str(exc))
        else:
            print(f"skelscope: wrote {path}")
    if scripted:
        summary = window.scene.scores()
        if summary is not None:
            print("\n".join(_summary_lines(summary)))
        for view in window.compare.views[-1:] if ab is not None else []:
            cells = [[view.cell(r, c) for c in range(4)] for r in range(len(view.rows))]
            print("\n".join(f"{label:24} A {a:>10}  B {b:>10}  B-A {d}" for label, a, b, d in cells))
        window.close()
        return 1 if window.bug else 0
    return None


def fit_view_size(app: QtWidgets.QApplication, window: WindowApi, size: tuple[int, int]) -> None:
    """Resize the window so that the 3D view is ``size`` pixels (a picture at scale 1 is that big):
    a saved camera then frames the data as it did. ValueError when the window cannot get there."""
    want_w, want_h = int(size[0]), int(size[1])
    view, win = window.view.widget, window.widget
    ratio = view.devicePixelRatioF()
    for _ in range(4):
        dw, dh = round(want_w / ratio) - view.width(), round(want_h / ratio) - view.height()
        if not dw and not dh:
            break
        win.resize(win.width() + dw, win.height() + dh)
        app.processEvents()
    got = (round(view.width() * ratio), round(view.height() * ratio))
    if got != (want_w, want_h):
        raise ValueError(f"--size {want_w} {want_h}: the 3D view could only be made {got[0]} x {got[1]} pixels "
                         "(a window manager or the window's minimum size)")


def _summary_lines(summary: dict[str, Any]) -> list[str]:
    from .panels.summary import COLUMNS, ROWS, summary_cells

    cells = summary_cells(summary)
    width = max(len(r) for r in ROWS)
    lines = [f"{'':{width}}  {COLUMNS[0]:>28}  {COLUMNS[1]:>28}"]
    lines += [f"{row:{width}}  {a:>28}  {b:>28}" for row, (a, b) in zip(ROWS, cells)]
    return lines


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


def _start_ab(window: WindowApi, ab: tuple[str, Any] | None) -> None:
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
        QtCore.QTimer.singleShot(0, window, lambda: window.compare.compare_arrays(skeletal, curve, name))

    window.session.evaluated.connect(start_b)


def _save_ab_picture(app: QtWidgets.QApplication, window: WindowApi, path: str, scripted: bool) -> int:
    """The A/B window (split view and table) as PNG; 0, or the exit status of a failure."""
    from .compare_view import AB_SIZE
    from .exports import write_png

    views = [v for v in window.compare.views if v.isVisible()]
    if not views:
        return fail("the A/B view did not open", 1 if window.bug else 2) if scripted else 0
    views[-1].resize(*AB_SIZE)  # a picture of the same size on every screen (the window fits the user's)
    app.processEvents()
    try:
        out = write_png(path, views[-1].picture(), window.input_files())
    except (ValueError, OSError) as exc:
        if scripted:
            return fail(str(exc))
        window.show_error("Screenshot failed", str(exc))
        return 0
    print(f"skelscope: wrote {out}")
    return 0


def _wait_for_runner(app: QtWidgets.QApplication, session: Session) -> None:
    from PySide6 import QtCore

    if not session.runner.running:
        return
    loop = QtCore.QEventLoop()
    session.runner.finished.connect(loop.quit)
    if session.runner.running:
        loop.exec()
    app.processEvents()
