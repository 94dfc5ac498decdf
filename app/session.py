"""The viewer's controller: loads files into the scene, runs evaluate / skeletonize in the worker.

No widgets here: dialogs are reached through the ``error`` signal and the ``ask`` callback, which the
main window connects to message boxes (and tests or the scripted mode replace).
"""

from __future__ import annotations

import dataclasses
import os
import threading
from typing import Any, Callable

from PySide6 import QtCore

from skelcore.errors import SkelInputError
from skelcore.params import Params

from .edit_scoring import DEFECTS_TASK, UPDATE_LOCK, UPDATING, defects_job, defects_pending, scores_job
from .loading import ROLES, Ask, assign_roles
from .scene import Scene, SceneEvent
from .worker import TaskRunner

__all__ = ["Session", "preload_engine", "PROCESS_FROM", "UPDATE_LOCK"]


PROCESS_FROM = 200_000
"""Evaluations of at least this many points (cloud + skeletal set) run in a child process
(:mod:`skelscope.engine_process`): Cancel and quit are then a kill, and the window never waits for the
engine's GIL. Smaller ones run in a thread (no process start, ~1 s of imports)."""
FRAME_HOLD_S = 1.0
"""After an edit the view waits at most this long for the first phase's scores, so the update draws
the edited curve once, coloured: a frame drawn meanwhile (0.09 CPU s at 100k points under software GL,
on both cores) slows the update and so the recoloured frame; on a loaded machine a pruned branch's
first phase took 0.5-1 s with it (docs/performance.md 6.10)."""


def preload_engine() -> None:
    """Import skelcore's metrics (scipy's KD-trees and the metric modules, ~0.5 s) in the background
    once the window is up: the start-up does without them, and the first evaluation need not wait."""

    def load() -> None:
        import skelcore.stages  # noqa: F401

    threading.Thread(target=load, name="skelscope-preload-engine", daemon=True).start()


class Session(QtCore.QObject):
    error = QtCore.Signal(str, str, str)  # title, one-line message, details ("" when none)
    message = QtCore.Signal(str)  # status-bar text
    loaded = QtCore.Signal(str, str)  # role, path
    evaluated = QtCore.Signal(object)  # the Evaluation now shown (complete: never an edit's first phase)
    #: an edit's first phase shown: its scores, the curve's defects still updating (skelscope.edit_scoring)
    scores_shown = QtCore.Signal(object)
    stale_changed = QtCore.Signal(str)  # why the shown results are out of date ("" when they are not)

    def __init__(self, scene: Scene | None = None, parent: QtCore.QObject | None = None) -> None:
        super().__init__(parent)
        self.scene = scene or Scene()
        self.runner = TaskRunner(self)
        self.ask: Ask = lambda question, options: options[0] if options else None
        self.params_provider: Callable[[], Params] = Params
        #: "auto" or "reverse" (docs/metrics.md 5.1), e.g. the settings panel's choice
        self.correspondence_provider: Callable[[], str] = lambda: "auto"
        #: ``remove_outliers`` / ``cap_openings`` for skelcore.evaluate (the settings panel's real-scan options)
        self.scan_options_provider: Callable[[], dict[str, bool]] = dict
        #: sets that choice (a drop answered "skeletal set (no correspondence: reverse projection)")
        self.set_correspondence: Callable[[str], None] = lambda key: None
        #: ``ask_file(title) -> path or None``: an index file for a skeletal set (the window: a file dialog)
        self.ask_file: Callable[[str], str | None] = lambda title: None
        #: evaluations of at least this many points (cloud + skeletal set) run in a child process
        self.process_from = PROCESS_FROM
        self.auto_evaluate = True
        #: ``after_scores(fn)``: ``fn()`` once an edit's first phase is on screen (the window: after its
        #: frame), when the second phase may start
        self.after_scores: Callable[[Callable[[], None]], None] = lambda fn: fn()
        #: ``hold_frames(seconds)`` / ``release_frames()``: the view's frames wait for an edit's scores
        #: (at most FRAME_HOLD_S), so the edited curve and its colours come in one frame
        self.hold_frames: Callable[[float], None] = lambda seconds: None
        self.release_frames: Callable[[], None] = lambda: None
        #: ``draw_now()``: the view's pending frame drawn at once (an edit's first phase landed: its
        #: recoloured frame before Qt repaints the panels)
        self.draw_now: Callable[[], None] = lambda: None
        #: the sensors' positions (viewpoint-aware boundedness and centeredness; [] = the paper's scores)
        self.viewpoints: list[tuple[float, float, float]] = []
        self.runner.succeeded.connect(self._task_succeeded)
        self.runner.failed.connect(self._task_failed)
        self.runner.finished.connect(lambda name: self.check_stale())
        # an edit's first phase cancelled or dropped: its curve is drawn now, not when the hold ends
        self.runner.cancelled.connect(lambda name: self.release_frames())
        self.scene.subscribe(self._on_scene)

    # ---- loading --------------------------------------------------------------------------
    def load_files(self, paths: list[str]) -> list[tuple[str, str]]:
        """Load files dropped or named together, deciding each one's role (see :mod:`skelscope.loading`).

        A file that fails shows its loader's one-line message; the others and what was loaded survive.
        Returns the (role, path) pairs loaded.
        """
        from skelcore.io import load_any

        items, failures = [], []
        for path in paths:
            try:
                items.append(load_any(path))
            except SkelInputError as exc:
                failures.append(str(exc))
            except Exception as exc:  # noqa: BLE001 - a loader bug must not take the window down
                failures.append(f"{path}: {type(exc).__name__}: {exc}")
        if failures:
            self.error.emit("Could not load", "\n".join(failures), "")
        cloud = self.scene.cloud
        done = []
        skeleton_loaded = any(name in self.scene.layers for name in ("skeletal", "curve"))
        assignments = assign_roles(items, None if cloud is None else cloud.n_points, self.ask, skeleton_loaded)
        indices = {}
        for a in assignments:  # the index file is chosen before anything changes: cancelling it skips the set
            if a.role == "skeletal" and a.correspondence == "index":
                n_cloud = next((len(b.loaded.points) for b in assignments if b.role == "cloud"), None)
                n_cloud = n_cloud if n_cloud is not None else (cloud.n_points if cloud is not None else 0)
                indices[id(a)] = self._choose_index(a.loaded.path, len(a.loaded.points), n_cloud)
        assignments = [a for a in assignments if indices.get(id(a), True) is not None]
        with self.batch():
            roles = {a.role for a in assignments}
            if "cloud" in roles:
                decided = next(a.keep_skeleton for a in assignments if a.role == "cloud")
                self._new_cloud_over_skeleton(keep=roles - {"cloud"}, decided=decided)
            for a in assignments:
                if a.role == "skeletal" and a.correspondence is not None:
                    index, index_path = indices.get(id(a)) or (None, None)
                    self.scene.set_skeletal(a.loaded.points, a.loaded.path, index, index_path)
                    self._loaded(a.role, a.loaded.path)
                    self.set_correspondence("reverse" if a.correspondence == "reverse" else "auto")
                    how = ("Settings > correspondence set to reverse projection" if a.correspondence == "reverse"
                           else f"with the index {os.path.basename(str(index_path))}")
                    self.message.emit(f"loaded {os.path.basename(a.loaded.path)} as the skeletal point set ({how})")
                else:
                    self._apply(a.role, a.loaded.points if a.role != "curve" else a.loaded.curve, a.loaded.path)
                done.append((a.role, a.loaded.path))
        return done

    def _choose_index(self, skeletal_path: str, n_skeletal: int, n_cloud: int) -> tuple[Any, str] | None:
        """Ask for the index file of the skeletal set at ``skeletal_path`` and read it (one line error
        and None when it does not fit, or None when no file was chosen)."""
        from skelcore.io.correspondence_files import load_skeletal_index

        path = self.ask_file(f"Index file of {os.path.basename(skeletal_path)} (one cloud row per skeletal point)")
        if not path:
            self.message.emit(f"{os.path.basename(skeletal_path)} skipped: no index file chosen")
            return None
        try:
            return load_skeletal_index(path, n_skeletal, n_cloud), str(path)
        except SkelInputError as exc:
            self.error.emit("Could not load the skeletal index", str(exc), "")
            return None

    def load_index(self, path: str) -> bool:
        """File > Open skeletal index…: one cloud row per point of the loaded skeletal set (docs/metrics.md 5.1);
        the correspondence setting goes back to "as loaded", which uses it."""
        from skelcore.io.correspondence_files import load_skeletal_index

        sk, cloud = self.scene.skeletal, self.scene.cloud
        if sk is None or cloud is None:
            self.error.emit("Skeletal index", "load a cloud and a skeletal point set first", "")
            return False
        try:
            index = load_skeletal_index(path, sk.n_points, cloud.n_points)
        except SkelInputError as exc:
            self.error.emit("Could not load the skeletal index", str(exc), "")
            return False
        with self.batch():
            self.set_correspondence("auto")
            self.scene.set_skeletal_index(index, str(path))
        self.message.emit(f"loaded {os.path.basename(str(path))} as the skeletal set's index")
        return True

    def set_viewpoints(self, viewpoints: Any) -> None:
        """The scan's viewpoints (x y z each, the cloud's units) for the next evaluations (the engine's
        ``viewpoints=``); the shown results become stale until re-evaluated. [] goes back to the paper's
        scores. ValueError for anything but finite triples."""
        import math

        pts = [tuple(float(v) for v in p) for p in (viewpoints or [])]
        if any(len(p) != 3 or not all(math.isfinite(v) for v in p) for p in pts):
            raise ValueError("a viewpoint is three finite numbers x y z")
        self.viewpoints = pts
        self.message.emit("viewpoint " + ("; ".join(" ".join(f"{v:.6g}" for v in p) for p in pts) if pts else "cleared")
                          + ": re-evaluate to use it")
        self.check_stale()

    def map_skeleton(self, scale: float, offset: tuple[float, float, float]) -> bool:
        """Evaluate > Map skeleton into the cloud's frame: the skeleton layers times ``scale`` plus
        ``offset`` (a ``frame`` warning's suggestion), then evaluated again."""
        try:
            with self.batch():
                self._same_set = True
                try:
                    self.scene.map_skeleton(scale, offset)
                finally:
                    self._same_set = False
        except ValueError as exc:
            self.error.emit("Map skeleton", str(exc), "")
            return False
        self.message.emit(f"skeleton mapped by scale {scale:.6g} and offset {' '.join(f'{v:.6g}' for v in offset)}")
        return True

    KEEP_SKELETON = ("clear it", "keep it")

    def _new_cloud_over_skeleton(self, keep: set[str] = frozenset(), decided: bool | None = None) -> None:
        """A new cloud replaces the loaded one: the loaded skeleton layers (other than those in
        ``keep``, which arrive with the cloud) describe the old cloud, so ask whether to keep them,
        unless the drop's question answered it already (``decided``: one question, not
        two contradicting ones); the default (the question's first answer) clears them."""
        old = [name for name in ("skeletal", "curve") if name in self.scene.layers and name not in keep]
        if not old or self.scene.cloud is None:
            return
        if decided is not None:
            choice = self.KEEP_SKELETON[1] if decided else self.KEEP_SKELETON[0]
        else:
            what = " and ".join(_ROLE_TITLES[name] for name in old)
            choice = self.ask(f"A new cloud replaces the loaded one. The loaded {what} was made from the old cloud: "
                              "clear it or keep it?", list(self.KEEP_SKELETON))
        if choice != self.KEEP_SKELETON[1]:
            for name in old:
                self.scene.remove_layer(name)

    # ---- layers ---------------------------------------------------------------------------
    def close_layer(self, role: str) -> None:
        """File > Close / the panel's remove button: drop one layer (and the results with it)."""
        if role not in ROLES:
            raise ValueError(f"unknown role {role!r}")
        self.scene.remove_layer(role)
        self._after_layers_changed()

    def close_all(self) -> None:
        self.runner.discard()
        self.scene.clear()
        self._after_layers_changed()

    def swap_roles(self) -> None:
        """The cloud becomes the skeletal set and the skeletal set the cloud (Display panel)."""
        with self.batch():
            self.scene.swap_cloud_and_skeletal()

    def _after_layers_changed(self) -> None:
        self._inputs_changed = False  # closing is not an input to evaluate: no automatic run
        if not self.scene.layers:
            self._had_result = False
        self.check_stale()

    # ---- stale results --------------------------------------------------------------------
    _had_result = False

    def stale_reason(self) -> str:
        """Why the results on screen are not those of the current inputs and settings: "settings
        changed" (an evaluation is shown, the Settings panel now differs from its parameters; the
        thresholds re-score at once and never make it stale), "inputs changed" (the shown results
        were dropped with the inputs they described and nothing runs), "" otherwise."""
        ev = self.scene.evaluation
        if ev is None:
            running = self.runner.current_name == "evaluation"
            return "inputs changed" if self._had_result and self.scene.can_evaluate() and not running else ""
        try:
            now = self.params()
        except ValueError:
            return "settings changed"
        shown = ev.params
        scan = getattr(ev, "scan", None)
        used = [tuple(float(v) for v in p) for p in (scan.viewpoints if scan is not None else [])]
        if self._shown_viewpoints is not None and self._shown_viewpoints != self.viewpoints:
            return "settings changed"
        if self._shown_viewpoints is None and used != self.viewpoints and (used or self.viewpoints):
            return "settings changed"
        if self._shown_correspondence is not None and self.correspondence_provider() != self._shown_correspondence:
            return "settings changed"
        if self._shown_scan_options is not None and self.scan_options_provider() != self._shown_scan_options:
            return "settings changed"
        return "" if same_but_thresholds(now, shown) else "settings changed"

    _shown_correspondence: str | None = None  # what the shown evaluation was asked for (None: unknown)
    _shown_viewpoints: list | None = None  # the viewpoints the shown evaluation was asked with (None: unknown)
    _requested_viewpoints: list | None = None
    _requested_correspondence: str | None = None
    _shown_scan_options: dict | None = None  # the real-scan options the shown evaluation was asked with
    _requested_scan_options: dict | None = None

    def check_stale(self) -> None:
        reason = self.stale_reason()
        if reason != self._stale:
            self._stale = reason
            self.stale_changed.emit(reason)

    _stale = ""

    def load_as(self, role: str, path: str) -> bool:
        """File > Open for one role; False (and an error dialog) when the file does not load."""
        try:
            data = _read(role, path)
        except SkelInputError as exc:
            self.error.emit("Could not load", str(exc), "")
            return False
        with self.batch():
            if role == "cloud":
                self._new_cloud_over_skeleton()
            self._apply(role, data, path)
        return True

    def load_roles(self, paths: dict[str, str]) -> list[str]:
        """Replace everything by these files, each in its role (a saved session, a recent set): one
        evaluation after the last. Returns the one-line messages of the files that did not load,
        for the caller to show together (nothing is shown here); the others are loaded."""
        for role in paths:
            if role not in ROLES:
                raise ValueError(f"unknown role {role!r}")
        failures, loaded = [], {}
        for role in ROLES:
            if role in paths:
                try:
                    loaded[role] = _read(role, paths[role])
                except SkelInputError as exc:
                    failures.append(str(exc))
        self.runner.discard()
        with self.batch():
            self.scene.clear()
            for role, data in loaded.items():
                self._apply(role, data, paths[role])
        return failures

    def show_arrays(self, cloud: Any, skeletal: Any = None, curve: Any = None, evaluation: Any = None) -> None:
        """Show in-memory inputs (a study variant) in place of the loaded ones; evaluated
        unless its ``evaluation`` is given."""
        with self.batch():
            self.scene.set_cloud(cloud, None)
            for name, data in (("skeletal", skeletal), ("curve", curve)):
                if data is None:
                    self.scene.remove_layer(name)
                else:
                    self._apply(name, data, None)
            if evaluation is not None:
                self._inputs_changed = False
                self._shown_correspondence = None
                self._shown_viewpoints = None
                self._shown_scan_options = None
                self.scene.set_evaluation(evaluation)
                self._had_result = True
                self.evaluated.emit(evaluation)
        self.check_stale()

    def _apply(self, role: str, data: Any, path: str | None) -> None:
        if role == "cloud":
            self.scene.set_cloud(data, path)
        elif role == "skeletal":
            self.scene.set_skeletal(data, path)
        else:
            self.scene.set_curve(data, path)
        self._loaded(role, path)

    def _loaded(self, role: str, path: str | None) -> None:
        if path:
            self.loaded.emit(role, str(path))
            self.message.emit(f"loaded {os.path.basename(str(path))} as the {_ROLE_TITLES[role]}")

    class _Batch:
        def __init__(self, session: "Session") -> None:
            self.session = session

        def __enter__(self) -> None:
            self.session._batch_depth += 1

        def __exit__(self, *exc: object) -> None:
            self.session._batch_depth -= 1
            if self.session._batch_depth == 0 and self.session._inputs_changed:
                self.session._inputs_changed = False
                if self.session.auto_evaluate and self.session.scene.can_evaluate():
                    self.session._auto_start()

    _batch_depth = 0
    _inputs_changed = False

    _auto_token = 0

    def _auto_start(self) -> None:
        """The evaluation of newly loaded inputs starts once the window has drawn them
        (``after_render``): a worker started at once competes with the first frame for the cores
        (6.8-10.4 s to the first frame of a 1M cloud with its 1M skeletal set)."""
        self._auto_token += 1
        token = self._auto_token

        def start() -> None:
            if token == self._auto_token and self.scene.can_evaluate() and self.scene.evaluation is None:
                self.start_evaluation()

        sk = self.scene.skeletal
        big = self.scene.cloud.n_points + (0 if sk is None else sk.n_points) >= self.process_from
        (self.after_render if big else (lambda fn: fn()))(start)

    #: ``after_render(fn)``: ``fn()`` once the window has painted the current scene (the main window
    #: passes its view's); at once by default
    after_render: Callable[[Callable[[], None]], None] = staticmethod(lambda fn: fn())

    def batch(self) -> "Session._Batch":
        """Several files loaded together start one evaluation, after the last one."""
        return Session._Batch(self)

    def _on_scene(self, event: SceneEvent) -> None:
        if event.kind == "layer" and event.layer == "skeletal":
            self._new_skeletal_set()
        if event.kind == "layer":
            self.evaluation_cancelled = False
            # The running evaluation describes old inputs: drop it (its result will never land);
            # not the edited curve's own scoring, started just before its swap (show_edited_curve).
            if self.runner.current_name in ("evaluation", DEFECTS_TASK) and not self._scoring_swap:
                self.runner.discard()
            self._inputs_changed = True
        if event.kind in ("layer", "quantities") and not self._swapping_curve:
            self.check_stale()

    _correspondence_of: Any = None  # the skeletal layer the correspondence setting was chosen for
    _same_set = False  # the skeletal layer being replaced is the same set (mapped into the cloud's frame)

    def _new_skeletal_set(self) -> None:
        """A correspondence choice belongs to the skeletal set it was made for: another set (loaded,
        swapped, skeletonized or closed) starts "as loaded" again, and its load decides (a drop's
        answer, an index file). A set mapped into the cloud's frame stays the same set."""
        layer = self.scene.skeletal
        if layer is self._correspondence_of:
            return
        self._correspondence_of = layer
        if not self._same_set and self.correspondence_provider() != "auto":
            self.set_correspondence("auto")

    # ---- computing ------------------------------------------------------------------------
    def params(self) -> Params:
        """The Settings panel's parameters with the summary's thresholds: the same (frozen) object while
        neither changes (asked several times per edit: docs/performance.md 6.10)."""
        chosen, beta, c = self.params_provider(), self.scene.beta_star, self.scene.c_star
        made = self._params_made
        if made is None or made[0] is not chosen or made[1] != beta or made[2] != c:
            made = self._params_made = (chosen, beta, c, chosen.replace(beta_star=beta, c_star=c))
        return made[3]

    _params_made: tuple | None = None

    def start_evaluation(self, params: Params | None = None) -> bool:
        """Evaluate the loaded inputs in the worker thread (cancelling any run in progress)."""
        import skelcore

        scene = self.scene
        if not scene.can_evaluate():
            self.message.emit("load a cloud and a skeletal point set or a curve skeleton first")
            return False
        try:
            params = params or self.params()
        except ValueError as exc:
            self.error.emit("Invalid parameters", str(exc), "")
            return False
        cloud = scene.cloud.points
        skeletal = None if scene.skeletal is None else scene.skeletal.points
        curve = None if scene.curve is None else scene.curve.curve
        inputs = {k: v for k, v in scene.input_paths().items() if v}
        correspondence = self.correspondence_provider()
        index = None
        if correspondence != "reverse" and scene.skeletal is not None and scene.skeletal.index is not None:
            index = scene.skeletal.index  # reverse projection, when chosen, replaces the index (as the CLI's CGAL rule)
            if scene.skeletal.index_path:
                inputs["skeletal_index"] = scene.skeletal.index_path
        self._requested_correspondence = correspondence
        self._requested_viewpoints = list(self.viewpoints)
        self._requested_scan_options = dict(self.scan_options_provider())
        kwargs = dict(skeletal=skeletal, curve=curve, params=params, inputs=inputs, correspondence=correspondence,
                      skeletal_index=index, viewpoints=[list(p) for p in self.viewpoints] or None,
                      **self._requested_scan_options)
        self._evaluated_layers = (scene.cloud, scene.skeletal, scene.curve)
        self.evaluation_cancelled = False
        if len(cloud) + (0 if skeletal is None else len(skeletal)) >= self.process_from:
            def restore(ev: Any) -> Any:  # the child does not send the cloud back
                if ev.cloud is None:
                    ev.cloud = cloud
                return ev

            self.runner.start_process("evaluate", dict(cloud=cloud, **kwargs), "evaluation", restore)
        else:
            def job(progress: Any, cancel: Callable[[], bool]) -> Any:
                # skelcore.evaluate is resolved (and, the first time, imported) in the worker thread
                return skelcore.evaluate(cloud, progress=progress, cancel=cancel,
                                         on_stages=getattr(progress, "stages", None), **kwargs)

            self.runner.start(job, "evaluation")
        self.check_stale()
        self.message.emit("evaluating…")
        return True

    def show_edited_curve(self, curve: Any, known: Any = None, score: bool = True, edited: bool = True) -> str:
        """The curve layer becomes ``curve`` (an edit, its undo or redo) and is scored again: ``known``
        (the evaluation of ``curve`` kept by an undo step) is shown at once; else, when the shown
        evaluation is of the curve before, ``Evaluation.update`` runs in the worker (only the curve's
        samples that moved are scored again); else a full evaluation. A running evaluation is
        dropped first (its result can never land). Returns "known", "update", "full" or "" (nothing
        to score: no evaluation was shown and none was running). ``score=False`` only replaces the
        curve (a session's edits replayed while it loads: its own evaluation follows). ``edited=False``:
        the curve is the loaded one again (every edit undone)."""
        from skelcore.edit import content_hash
        from skelcore.stages.evaluation_source import EvaluationSource

        scene = self.scene
        old = scene.curve
        if old is None:
            raise ValueError("no curve skeleton loaded")
        base = scene.evaluation
        running = self.runner.current_name in ("evaluation", DEFECTS_TASK)  # a stale second phase too
        if running:
            self.runner.discard()
        if not score:
            with self.batch():
                scene.set_curve(curve, old.path, edited=edited)
            return ""
        src = None if base is None else getattr(base, "source", None)
        updatable = (base is not None and getattr(base, "curve", None) is not None and isinstance(src, EvaluationSource)
                     and src.args.get("curve") is not None and src.ctx is not None
                     and content_hash(base.curve.curve) == content_hash(old.curve)
                     and not self.stale_reason())  # under the settings shown: else evaluated afresh with the new
        if known is not None:
            try:
                now = self.params()
                if not same_but_thresholds(known.params, now):
                    known = None  # kept under other settings: scored again
            except ValueError:
                known = None
        update = updatable and known is None
        if update:
            self.hold_frames(FRAME_HOLD_S)  # released when the scores land (_task_succeeded, _task_failed)
            # The first phase starts before the curve is swapped and redrawn: the engine's kernels
            # run while this thread redraws (docs/performance.md 6.10).
            self._requested_correspondence = self._shown_correspondence
            self._requested_viewpoints = self._shown_viewpoints
            self._requested_scan_options = self._shown_scan_options
            self.evaluation_cancelled = False
            self.runner.start(scores_job(base, curve), "evaluation")  # the four metrics; the defects follow
        self._swapping_curve = True  # scored: not "inputs changed" meanwhile (a grey frame each way)
        self._scoring_swap = update
        try:
            with self.batch():
                scene.set_curve(curve, old.path, edited=edited)
                self._inputs_changed = False  # scored here, not by the automatic run
        finally:
            self._swapping_curve = self._scoring_swap = False
        if update:
            self._evaluated_layers = (scene.cloud, scene.skeletal, scene.curve)
            self.check_stale()
            self.message.emit("scoring the edited curve…")
            return "update"
        if known is not None:
            scene.set_evaluation(known)
            self._had_result = True
            self.check_stale()
            self.evaluated.emit(known)
            return "known"
        if base is None and not running and not self.auto_evaluate:
            self.check_stale()
            return ""
        started = self.start_evaluation()
        self.check_stale()
        return "full" if started else ""

    def start_skeletonize(self, params: Any = None, method: str | None = None) -> bool:
        """Skeletonize the loaded cloud in the worker; both results become layers.

        ``method`` "cao" (default) or "skelscope"; ``params`` its ``CaoParams`` / ``SkeletonizeParams``.
        """
        if self.scene.cloud is None:
            self.message.emit("load a cloud first")
            return False
        try:
            from skelcore.skeleton import skeletonize
        except ImportError as exc:
            self.error.emit("Skeletonize", f"the skeletonizer is not available ({exc})", "")
            return False
        params = params or None  # a menu action passes its checked state
        cloud = self.scene.cloud.points

        def job(progress: Callable[[float, str], None], cancel: Callable[[], bool]) -> Any:
            return skeletonize(cloud, params, progress=progress, cancel=cancel, method=method)

        self._skeletonized_cloud = self.scene.cloud
        self.runner.start(job, "skeletonization")
        self.message.emit("skeletonizing…")
        return True

    def cancel(self) -> None:
        """Cancel (Esc, the status bar's button): the window is free at once and no result of the
        task can land; its thread stops at the engine's next checkpoint."""
        name = self.runner.current_name
        if name == "evaluation":
            self.evaluation_cancelled = True  # before the runner says so: the window words the Summary
        self.runner.discard()
        if name:
            self.message.emit(f"{name} cancelled")

    @QtCore.Slot(str, object)
    def _task_succeeded(self, name: str, result: Any) -> None:
        scene = self.scene
        if name == "evaluation":
            if self._evaluated_layers != (scene.cloud, scene.skeletal, scene.curve):
                self.release_frames()
                return  # inputs changed meanwhile: this result describes other data
            if not defects_pending(result):
                self.release_frames()  # after this event's changes: one frame shows them all
            # else an edit's first phase: the frames stay held while its scores are set (the panels
            # then wait for the frame, docs/performance.md 6.10) and draw_now below draws it
            painted = threading.Event()
            if defects_pending(result):  # an edit's first phase: its defects in a second task, started
                # before the scores are shown, so every panel says "updating" at once (not "cancelled"
                # until the task's end refreshes it, after the frame: a second frame)
                self._defects_of = result
                self.runner.start(defects_job(result, painted), DEFECTS_TASK)
            scene.set_evaluation(result)
            self._shown_correspondence = self._requested_correspondence
            self._shown_viewpoints = self._requested_viewpoints
            self._shown_scan_options = self._requested_scan_options
            self._had_result = True
            self.check_stale()
            if defects_pending(result):
                self.after_scores(painted.set)  # it starts once the recoloured frame is on screen
                self.scores_shown.emit(result)
                self.draw_now()
                self.message.emit(f"scores of the edited curve shown; {UPDATING}")  # after the frame
                return
            total = result.timings.get("total") if result.timings else None
            self.message.emit("evaluation done" + (f" in {total:.2f} s" if total is not None else ""))
            self.evaluated.emit(result)
        elif name == DEFECTS_TASK:
            if scene.evaluation is not self._defects_of or self._evaluated_layers != (scene.cloud, scene.skeletal,
                                                                                     scene.curve):
                return  # another evaluation shown meanwhile
            scene.set_evaluation(result)
            self.check_stale()
            self.message.emit("the edited curve's defects updated")
            self.evaluated.emit(result)
        elif name == "skeletonization":
            if self._skeletonized_cloud is not scene.cloud:
                return
            from skelcore.curve import CurveSkeleton

            skeletal, curve = result
            if not isinstance(curve, CurveSkeleton):
                curve = CurveSkeleton.from_raw(*curve)
            with self.batch():
                scene.set_skeletal(skeletal, None)
                scene.set_curve(curve, None)
            self.message.emit(f"skeletonized: {len(skeletal)} skeletal points, {curve.n_vertices} curve vertices")

    @QtCore.Slot(str, object, str)
    def _task_failed(self, name: str, exc: Any, tb: str) -> None:
        self.release_frames()
        if isinstance(exc, (SkelInputError, ValueError)):
            self.error.emit(f"{name.capitalize()} failed", str(exc), "")
        else:
            self.error.emit(f"{name.capitalize()} failed", f"{type(exc).__name__}: {exc}", tb)
        self.message.emit(f"{name} failed")

    _evaluated_layers: tuple = ()
    _skeletonized_cloud: Any = None
    _defects_of: Any = None  # the first phase whose defects the DEFECTS_TASK finds
    _swapping_curve = False  # show_edited_curve replacing the curve it scores right after
    _scoring_swap = False  # ... whose first phase already runs (it describes the new curve: kept)
    #: the last evaluation was cancelled (Esc, Cancel) and neither a new run nor new inputs came since
    evaluation_cancelled = False


#: the parameters every evaluation reads (the thresholds beta* and c* re-score at once and never stale a result)
_SETTINGS = tuple(f.name for f in dataclasses.fields(Params) if f.name not in ("beta_star", "c_star"))


def same_but_thresholds(a: Params, b: Params) -> bool:
    """Whether ``a`` and ``b`` agree on every parameter but the thresholds: ``a`` with ``b``'s thresholds
    equals ``b`` (the dataclass' comparison, field by field), without making that copy."""
    return a is b or (type(a) is type(b) and all((x is y or x == y) for x, y in
                                                 ((getattr(a, n), getattr(b, n)) for n in _SETTINGS)))


_ROLE_TITLES = {"cloud": "cloud", "skeletal": "skeletal point set", "curve": "curve skeleton"}


def _read(role: str, path: str) -> Any:
    """The file's data for ``role`` (points, or a CurveSkeleton); SkelInputError with one line, also
    for a loader's own bug (the window must survive it)."""
    from skelcore.io import load_cloud, load_curve, load_points

    if role not in ROLES:
        raise ValueError(f"unknown role {role!r}")
    loader = {"cloud": load_cloud, "skeletal": load_points, "curve": load_curve}[role]
    try:
        return loader(path)
    except SkelInputError:
        raise
    except Exception as exc:  # noqa: BLE001 - a loader bug must not take the window down
        raise SkelInputError(f"{type(exc).__name__}: {exc}", path) from None
