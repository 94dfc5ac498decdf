"""Wires the support views into the main window: a pick shows the element's support in the
"Support" dock (2-D plot) and in the 3-D view (overlay); the Display panel's "only elements below the
threshold" box hides (and makes unpickable) every element whose value passes (beta > beta*, c > c*;
NaN stays shown).

Supports of clouds of BACKGROUND_POINTS or more are computed in a thread of their own (a direction map
of a 100k-point cloud takes seconds), the newest pick winning: a new pick, a new result and quitting
stop the computation still running (:class:`_Job`), which would otherwise share the cores and the
interpreter with the new one until its end. Made by :class:`skelscope.main_window.MainWindow`
through its public interface (:class:`skelscope.window_api.WindowApi`): it listens to ``element_picked`` and
subscribes to the scene after the view, so its overlay and filter are applied after the view's redraw.
"""

from __future__ import annotations

import ctypes
import threading
from typing import Any

import numpy as np
import pyvista as pv
from PySide6 import QtCore, QtWidgets

from .panels.support import SupportPanel
from .scene import SceneEvent
from .scene.supports import ElementSupport, element_support
from .view.actors import display_coordinates
from .view.picking import pick_layout
from .view.style import MAGENTA
from .view.support_overlay import SupportOverlay
from .window_api import LEFT, WindowApi

__all__ = ["SupportController", "SupportCancelled", "below_threshold"]

# scene-view actor -> (layer, quantity location) the filter replaces
_FILTERED = {"skeletal": ("skeletal", "points"), "curve-samples": ("curve", "samples"),
             "curve-vertices": ("curve", "vertices")}


def below_threshold(values: np.ndarray, threshold: float) -> np.ndarray:
    """The elements an overall score does not count: value <= threshold, or NaN (docs/metrics.md 2-3)."""
    v = np.asarray(values, dtype=float)
    return ~(v > threshold)


BACKGROUND_POINTS = 20_000


class SupportCancelled(BaseException):
    """Raised inside a support computation that a newer pick (or a new result, or quitting) replaced (not
    an Exception: no handler in the engine swallows it)."""


class _Job:
    """One support computed in a daemon thread; :meth:`cancel` stops it at the thread's next Python
    step (an exception raised into the thread, landing after the numpy call under way: a few
    milliseconds, the direction map running in small chunks) or at :meth:`checkpoint`, which the
    cloud's tree build polls while its C threads run without the interpreter. Nothing joins it."""

    def __init__(self, compute: Any, deliver: Any) -> None:
        self._compute, self._deliver = compute, deliver
        self._lock = threading.Lock()
        self._computing = True
        self.cancelled = False
        self.thread = threading.Thread(target=self._run, name="skelscope-support", daemon=True)

    def start(self) -> None:
        self.thread.start()

    def checkpoint(self, _fraction: float = 0.0) -> None:
        """Raise :class:`SupportCancelled` once cancelled (the engine's checkpoint signature)."""
        if self.cancelled:
            with self._lock:  # cancel() has raised it into this thread too, or will not now
                self._computing = False
            raise SupportCancelled

    def cancel(self) -> None:
        with self._lock:
            self.cancelled = True
            if self._computing and self.thread.ident is not None and self.thread.is_alive():
                ctypes.pythonapi.PyThreadState_SetAsyncExc(ctypes.c_ulong(self.thread.ident),
                                                           ctypes.py_object(SupportCancelled))

    def _run(self) -> None:
        try:
            try:
                out: Any = self._compute()
            except SupportCancelled:
                raise
            except Exception as exc:  # noqa: BLE001 - reported in the status bar, never a crash
                out = exc
            with self._lock:
                self._computing = False
            if not self.cancelled:
                self._deliver(out)
        except SupportCancelled:
            pass  # replaced: nothing to deliver
        except RuntimeError:  # the window closed meanwhile
            pass


class SupportController(QtCore.QObject):
    ready = QtCore.Signal(int, object, object)  # request token, info, ElementSupport or the exception

    def __init__(self, window: WindowApi) -> None:
        super().__init__(window.widget)
        self.window = window
        self.scene = window.scene
        self.view = window.view
        self.panel = SupportPanel(window.widget)
        self.overlay = SupportOverlay(self.view)
        self.info: dict[str, Any] | None = None
        self.support: ElementSupport | None = None
        self.filter_on = False
        self._filter_names: list[str] = []
        self.filter_meshes: dict[str, pv.PolyData] = {}  # filter actor name -> the points it draws
        window.add_dock("Support", self.panel, LEFT, below="Picked element")
        self.filter_box = QtWidgets.QCheckBox("only elements below the threshold")
        self.filter_box.setToolTip("hide every element the overall score counts (beta > beta*, c > c*); NaN stays")
        self.filter_box.toggled.connect(self.set_filter)
        window.add_display_option(self.filter_box)
        self.background_points = BACKGROUND_POINTS
        self._token = 0
        self._job: _Job | None = None
        self.busy = False
        self.ready.connect(self._ready)
        window.element_picked.connect(self.show_element)
        window.closing.connect(self.cancel)
        self.scene.subscribe(self._on_scene)
        self._sync_filter_box()

    # ---- picking --------------------------------------------------------------------------
    def show_element(self, info: dict[str, Any] | None) -> ElementSupport | None:
        """Compute and show the support of ``info`` for the metric on screen (None clears); for a
        big cloud in a thread, shown when done (returns None meanwhile)."""
        self.info = info
        self._token += 1
        self.cancel()
        ev, metric = self.scene.evaluation, self.scene.metric
        if ev is None or info is None or len(ev.cloud) < self.background_points:
            try:
                support = element_support(ev, info, metric)
            except (ValueError, IndexError) as exc:
                support = exc
            self._ready(self._token, info, support)
            return self.support
        self.busy = True
        self.overlay.clear()
        self.panel.show_support(ElementSupport("none", info.get("element", ""), int(info["index"]), metric,
                                               reason=f"computing the {metric} support…"))
        token = self._token
        job = _Job(None, lambda out: self.ready.emit(token, info, out))
        job._compute = lambda: element_support(ev, info, metric, job.checkpoint)
        self._job = job
        self._job.start()
        return None

    def cancel(self) -> None:
        """Stop the support still computing, if any (its result would be dropped anyway)."""
        job, self._job = self._job, None
        if job is not None:
            job.cancel()

    def _ready(self, token: int, info: Any, support: Any) -> None:
        if token != self._token:
            return  # a newer pick (or a new result) replaced this one
        self.busy = False
        if isinstance(support, Exception):
            self.window.show_message(f"support: {support}")
            support = None
        self.support = support
        ev = self.scene.evaluation
        self.panel.show_support(support, ev.normalization.scale if ev is not None else 1.0)
        self.overlay.show(support)

    def _on_scene(self, event: SceneEvent) -> None:
        if event.kind in ("layer", "quantities"):
            self.info = None
            self._token += 1  # a support still computing describes the old result
            self.cancel()
            self.busy = False
            self.overlay.clear()
            if self.support is not None:
                self.support = None
                self.panel.show_support(None)
        elif event.kind == "colouring" and self.info is not None:
            self.show_element(self.info)  # the metric changed: that metric's support
        if event.kind in ("layer", "quantities", "colouring", "thresholds", "display"):
            self._sync_filter_box()
            if self.filter_on:
                self._apply_filter()

    # ---- filter ---------------------------------------------------------------------------
    def _sync_filter_box(self) -> None:
        ok = self.scene.threshold_for(self.scene.metric) is not None and self.scene.evaluation is not None
        self.filter_box.setEnabled(ok)
        self.filter_box.setToolTip("hide every element the overall score counts (beta > beta*, c > c*); NaN stays"
                                   if ok else "needs an evaluation and a metric with a threshold (not smoothness)")

    def set_filter(self, on: bool) -> None:
        self.filter_on = bool(on)
        if self.filter_box.isChecked() != self.filter_on:
            self.filter_box.blockSignals(True)
            self.filter_box.setChecked(self.filter_on)
            self.filter_box.blockSignals(False)
        self._apply_filter()

    def filtered_counts(self) -> dict[str, tuple[int, int]]:
        """Per filtered actor: (elements shown, elements in all)."""
        out = {}
        for key, (layer_name, location) in _FILTERED.items():
            mask = self._mask(layer_name, location)
            if mask is not None:
                out[key] = (int(mask.sum()), int(mask.size))
        return out

    def _mask(self, layer_name: str, location: str) -> np.ndarray | None:
        threshold = self.scene.threshold_for(self.scene.metric)
        layer = self.scene.layers.get(layer_name)
        if threshold is None or layer is None:
            return None
        q = layer.quantity(self.scene.metric)
        if q is None or q.location != location:
            return None
        return below_threshold(q.values, threshold)

    def _apply_filter(self) -> None:
        plotter = self.view.plotter
        for name in self._filter_names:
            plotter.remove_actor(name, render=False)
        self._filter_names = []
        self.filter_meshes = {}
        actors = self.view._actors
        active = self.filter_on and self.filter_box.isEnabled()
        for key, (layer_name, location) in _FILTERED.items():
            actor = actors.get(key)
            layer = self.scene.layers.get(layer_name)
            mask = self._mask(layer_name, location) if active else None
            if actor is None or layer is None:
                continue
            if mask is None:
                self.view._pick_coords.pop(key, None)  # rebuilt from every element at the next pick
                actor.SetVisibility(self.view._shown(key, layer))
                if f"{key}-lod" in actors:
                    actors[f"{key}-lod"].SetVisibility(self.view._shown(f"{key}-lod", layer))
                continue
            actor.SetVisibility(False)
            # hidden elements cannot be picked: NaN coordinates are never near a click
            coords = np.array(self.view._sources[key], dtype=float)
            coords[~mask] = np.nan
            self.view._pick_coords[key] = pick_layout(coords)
            lod = actors.get(f"{key}-lod")
            if lod is not None:
                lod.SetVisibility(False)
            if not layer.visible or not mask.any():
                continue
            source = self.view._sources[key]
            q = layer.quantity(self.scene.metric)
            mesh = pv.PolyData(display_coordinates(np.asarray(source)[mask]))
            mesh.point_data.set_array(np.asarray(q.values, dtype=float)[mask], "values")
            name = f"filter-{key}"
            plotter.add_mesh(mesh, scalars="values", cmap=self.view._lookup_table(), clim=self.scene.colour_range(),
                             nan_color=MAGENTA, style="points", point_size=actor.prop.point_size + 3,
                             lighting=False, name=name, reset_camera=False, render=False, pickable=False,
                             show_scalar_bar=False)
            self._filter_names.append(name)
            self.filter_meshes[name] = mesh
        self.view.request_render()
