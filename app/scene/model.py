"""The scene model: the loaded layers, the current evaluation and the display choices, without Qt.

Every change goes through a ``Scene`` method, which emits a :class:`~skelscope.scene.events.SceneEvent`
to its subscribers (the 3D view and the panels redraw from it). Changing the thresholds updates
the centeredness quantities and the scores from the kept ``Evaluation``, never re-evaluating.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from skelcore.curve import CurveSkeleton
from skelcore.params import Params

from .events import Listener, SceneEvent
from .layers import METRICS, Layer, ScalarQuantity

__all__ = ["Scene", "STYLE_DEFAULTS"]

STYLE_DEFAULTS = {"spheres": False, "eye_dome": False, "axes": True}


class Scene:
    """Everything the viewer shows, and the current evaluation, without any Qt.

    Changing inputs drops the evaluation (its values would describe other data). Changing the
    thresholds recomputes only the centeredness quantities (the unbounded -> 0 rule of docs/metrics.md 3.3 depends on
    beta*) and the overall scores, through ``Evaluation.summary``: nothing is re-evaluated.
    """

    def __init__(self) -> None:
        self.layers: dict[str, Layer] = {}
        self.evaluation: Any = None  # skelcore.evaluation.Evaluation
        self.metric: str = "boundedness"
        self.clim: tuple[float, float] | None = None  # None: the metric's natural range [0, 1]
        self.edges_as_tubes: bool = False
        self.style: dict[str, bool] = dict(STYLE_DEFAULTS)  # figure options, see set_style
        defaults = Params()  # the thresholds until an evaluation brings its own
        self.beta_star: float = defaults.beta_star
        self.c_star: float = defaults.c_star
        self.stale: str = ""  # why the shown results are out of date ("settings changed"), "" when they are not
        self._listeners: list[Listener] = []

    # ---- events ---------------------------------------------------------------------------
    def subscribe(self, listener: Listener) -> None:
        self._listeners.append(listener)

    def unsubscribe(self, listener: Listener) -> None:
        if listener in self._listeners:
            self._listeners.remove(listener)

    def _emit(self, kind: str, layer: str | None = None) -> None:
        event = SceneEvent(kind, layer)
        for listener in list(self._listeners):
            listener(event)

    # ---- inputs ---------------------------------------------------------------------------
    @property
    def cloud(self) -> Layer | None:
        return self.layers.get("cloud")

    @property
    def skeletal(self) -> Layer | None:
        return self.layers.get("skeletal")

    @property
    def curve(self) -> Layer | None:
        return self.layers.get("curve")

    def set_cloud(self, points: np.ndarray, path: str | None = None) -> Layer:
        """The cloud; a kept skeletal set's index described the old cloud's rows, so it is dropped."""
        pts = _points(points)
        sk = self.skeletal
        if sk is not None and sk.index is not None:
            sk.index = sk.index_path = None
        # Dense clouds hide the skeleton: draw them lighter and smaller.
        size, opacity = (2.0, 0.35) if len(pts) <= 200_000 else (1.0, 0.2)
        layer = Layer("cloud", pts, path=path, point_size=size, opacity=opacity)
        return self._replace(layer)

    def set_skeletal(self, points: np.ndarray, path: str | None = None, index: np.ndarray | None = None,
                     index_path: str | None = None) -> Layer:
        """The skeletal point set; ``index`` maps its rows to cloud rows (docs/metrics.md 5.1), from ``index_path``."""
        layer = Layer("skeletal", _points(points), path=path, point_size=6.0,
                      index=None if index is None else np.asarray(index, dtype=np.int64), index_path=index_path)
        return self._replace(layer)

    def set_skeletal_index(self, index: np.ndarray | None, path: str | None = None) -> None:
        """Give the loaded skeletal set its index (File > Open skeletal index…), or take it away:
        an input change, so the evaluation goes."""
        layer = self.skeletal
        if layer is None:
            raise ValueError("no skeletal point set loaded")
        layer.index = None if index is None else np.asarray(index, dtype=np.int64)
        layer.index_path = path if index is not None else None
        self.clear_evaluation()
        self._emit("layer", "skeletal")

    def map_skeleton(self, scale: float, offset: tuple[float, float, float],
                     only: tuple[str, ...] = ("skeletal", "curve")) -> None:
        """Map the loaded skeleton layers (those named in ``only``) by ``v * scale + offset`` into the
        cloud's frame (a ``frame`` warning's remedy); mappings compose, ``Layer.mapping`` keeps the total."""
        from skelcore.skeleton_mapping import check_mapping, map_skeleton

        scale, offset = check_mapping(scale, offset)
        sk = self.skeletal if "skeletal" in only else None
        cv = self.curve if "curve" in only else None
        if sk is None and cv is None:
            raise ValueError("no skeleton loaded")
        points, curve = map_skeleton(None if sk is None else sk.points, None if cv is None else cv.curve, scale, offset)
        for layer in (sk, cv):
            if layer is None:
                continue
            s0, o0 = layer.mapping or (1.0, (0.0, 0.0, 0.0))
            total = (s0 * scale, tuple(float(o * scale + d) for o, d in zip(o0, offset)))
            if layer is sk:
                new = self.set_skeletal(points, sk.path, sk.index, sk.index_path)
            else:
                new = self.set_curve(curve, cv.path)
            new.mapping = total
    def set_curve(self, curve: CurveSkeleton, path: str | None = None, edited: bool = False) -> Layer:
        """The curve layer (``edited``: the curve of ``path`` changed by edits, said in the title)."""
        # Curve vertices smaller than the skeletal points (6): the skeletal set lies on the curve and
        # its colours must stay visible around each vertex.
        layer = Layer(
            "curve", np.asarray(curve.vertices, dtype=float), path=path, edges=np.asarray(curve.edges),
            curve=curve, point_size=4.0, edited=edited,
        )
        old = self.curve
        if edited and old is not None:
            layer.mapping = old.mapping
        return self._replace(layer)

    def remove_layer(self, name: str) -> None:
        """Close one layer (File > Close, the panel's remove button). The evaluation goes with it,
        except when one skeleton of two is closed: the other's column still describes the inputs
        left, so it stays (closing the curve keeps the skeletal set's results)."""
        if self.layers.pop(name, None) is not None:
            kept = _without_column(self.evaluation, name)
            if kept is None:
                self.clear_evaluation()
            else:
                self.evaluation = kept
            self._emit("layer", name)
            if kept is not None:
                self._emit("quantities")

    def clear(self) -> None:
        """Close every layer (File > Close all)."""
        for name in [n for n in ("curve", "skeletal", "cloud") if n in self.layers]:
            self.remove_layer(name)

    def swap_cloud_and_skeletal(self) -> None:
        """Exchange the cloud's and the skeletal set's data (a drop that guessed the roles wrong).
        Each role keeps its display choices; the evaluation, describing the old roles, is dropped."""
        cloud, skeletal = self.cloud, self.skeletal
        if cloud is None and skeletal is None:
            return
        self.clear_evaluation()
        for layer in (cloud, skeletal):
            if layer is not None:
                self.layers.pop(layer.name)
        if skeletal is not None:
            self.set_cloud(skeletal.points, skeletal.path)
        else:
            self._emit("layer", "cloud")
        if cloud is not None:
            self.set_skeletal(cloud.points, cloud.path)
        else:
            self._emit("layer", "skeletal")

    def _replace(self, layer: Layer) -> Layer:
        old = self.layers.get(layer.name)
        if old is not None:  # keep the user's display choices across reloads
            layer.visible, layer.point_size, layer.opacity = old.visible, old.point_size, old.opacity
        self.layers[layer.name] = layer
        self.clear_evaluation()
        self._emit("layer", layer.name)
        return layer

    def input_paths(self) -> dict[str, str | None]:
        return {name: layer.path for name, layer in self.layers.items()}

    def can_evaluate(self) -> bool:
        return self.cloud is not None and (self.skeletal is not None or self.curve is not None)

    # ---- evaluation -----------------------------------------------------------------------
    def clear_evaluation(self) -> None:
        had = self.evaluation is not None or any(layer.quantities for layer in self.layers.values())
        self.evaluation = None
        for layer in self.layers.values():
            layer.quantities.clear()
            layer.samples = layer.sample_edge = layer.sample_t = None
        if had:
            self._emit("quantities")

    def set_evaluation(self, evaluation: Any) -> None:
        """Attach an ``Evaluation``'s local values as quantities of the skeleton layers."""
        self.evaluation = evaluation
        self.beta_star = float(evaluation.params.beta_star)
        self.c_star = float(evaluation.params.c_star)
        sk, cv = self.skeletal, self.curve
        if evaluation.skeletal is not None and sk is not None:
            s = evaluation.skeletal
            sk.quantities.clear()
            sk.add_scalar_quantity("boundedness", s.boundedness)
            sk.add_scalar_quantity("centeredness", s.centeredness(self.beta_star))
            sk.add_scalar_quantity("smoothness", s.smoothness)
        if evaluation.curve is not None and cv is not None:
            c = evaluation.curve
            cv.quantities.clear()
            cv.samples = np.asarray(c.samples, dtype=float)
            cv.sample_edge = np.asarray(c.sample_edge)
            cv.sample_t = np.asarray(c.sample_t, dtype=float)
            cv.add_scalar_quantity("boundedness", c.sample_boundedness, location="samples")
            cv.add_scalar_quantity("centeredness", c.sample_centeredness(self.beta_star), location="samples")
            cv.add_scalar_quantity("smoothness", c.vertex_smoothness, location="vertices")
        self._emit("quantities")

    def set_thresholds(self, beta_star: float, c_star: float) -> None:
        """New beta*, c*: centeredness (unbounded -> 0, docs/metrics.md 3) and scores follow, no recomputation."""
        self.beta_star, self.c_star = float(beta_star), float(c_star)
        ev = self.evaluation
        if ev is not None:
            if ev.skeletal is not None and self.skeletal is not None:
                self.skeletal.add_scalar_quantity("centeredness", ev.skeletal.centeredness(self.beta_star))
            if ev.curve is not None and self.curve is not None:
                self.curve.add_scalar_quantity(
                    "centeredness", ev.curve.sample_centeredness(self.beta_star), location="samples"
                )
        self._emit("thresholds")

    def summary(self) -> dict[str, Any] | None:
        if self.evaluation is None:
            return None
        return self.evaluation.summary(self.beta_star, self.c_star)

    def scores(self) -> Any:
        """The overall scores at the scene's thresholds as one record (:class:`skelcore.scores.Scores`),
        None before an evaluation."""
        if self.evaluation is None:
            return None
        return self.evaluation.scores(self.beta_star, self.c_star)

    def threshold_for(self, metric: str) -> float | None:
        """The threshold an overall score counts against (none for smoothness, docs/metrics.md 4)."""
        return {"boundedness": self.beta_star, "centeredness": self.c_star}.get(metric)

    def set_stale(self, reason: str) -> None:
        """Mark the shown results out of date (the session's stale reason): the view and the plots
        draw them greyed until a re-run."""
        if reason != self.stale:
            self.stale = reason
            self._emit("stale")

    # ---- display --------------------------------------------------------------------------
    def set_metric(self, metric: str) -> None:
        if metric not in METRICS:
            raise ValueError(f"unknown metric {metric!r}: use one of {', '.join(METRICS)}")
        self.metric = metric
        self._emit("colouring")

    def set_clim(self, clim: tuple[float, float] | None) -> None:
        if clim is not None:
            lo, hi = float(clim[0]), float(clim[1])
            if not (math.isfinite(lo) and math.isfinite(hi) and lo < hi):
                raise ValueError(f"colour range needs finite min < max, got {clim!r}")
            clim = (lo, hi)
        self.clim = clim
        self._emit("colouring")

    def colour_range(self) -> tuple[float, float]:
        """The range of the colour map: the user's, else [0, 1], every metric's natural range."""
        return self.clim if self.clim is not None else (0.0, 1.0)

    def data_range(self) -> tuple[float, float] | None:
        """Finite min/max of the shown metric over every layer (for an 'auto' range)."""
        lo, hi = math.inf, -math.inf
        for q in self.shown_quantities():
            r = q.finite_range()
            if r is not None:
                lo, hi = min(lo, r[0]), max(hi, r[1])
        return None if lo > hi else (lo, hi)

    def shown_quantities(self) -> list[ScalarQuantity]:
        """The quantities of the selected metric on visible layers."""
        out = []
        for layer in self.layers.values():
            q = layer.quantities.get(self.metric)
            if q is not None and layer.visible:
                out.append(q)
        return out

    def n_invalid_shown(self) -> int:
        return sum(q.n_invalid for q in self.shown_quantities())

    def set_visible(self, name: str, visible: bool) -> None:
        layer = self.layers.get(name)
        if layer is not None and layer.visible != bool(visible):
            layer.visible = bool(visible)
            self._emit("display", name)

    def set_point_size(self, name: str, size: float) -> None:
        layer = self.layers.get(name)
        if layer is not None:
            layer.point_size = float(size)
            self._emit("display", name)

    def set_opacity(self, name: str, opacity: float) -> None:
        layer = self.layers.get(name)
        if layer is not None:
            layer.opacity = float(min(max(opacity, 0.0), 1.0))
            self._emit("display", name)

    def set_edges_as_tubes(self, tubes: bool) -> None:
        if bool(tubes) != self.edges_as_tubes:
            self.edges_as_tubes = bool(tubes)
            self._emit("display", "curve")

    def set_style(self, name: str, on: bool) -> None:
        """A figure option: 'spheres' (points as shaded spheres), 'eye_dome' (eye-dome lighting),
        'axes' (the orientation axes widget)."""
        if name not in STYLE_DEFAULTS:
            raise ValueError(f"unknown display option {name!r}: use one of {', '.join(STYLE_DEFAULTS)}")
        if self.style[name] != bool(on):
            self.style[name] = bool(on)
            self._emit("style", name)

    # ---- picking --------------------------------------------------------------------------
    def element_info(self, layer_name: str, location: str, index: int) -> dict[str, Any]:
        """Index, coordinates and every local value of one skeleton element (for the pick panel)."""
        layer = self.layers[layer_name]
        info: dict[str, Any] = {"layer": layer_name, "location": location, "index": int(index)}
        if location == "samples":
            if layer.samples is None:
                raise ValueError("the curve has no samples before an evaluation")
            info["element"] = "curve sample"
            info["xyz"] = tuple(float(v) for v in layer.samples[index])
            if layer.sample_edge is not None:
                info["edge"] = int(layer.sample_edge[index])
                info["t"] = float(layer.sample_t[index])
        else:
            info["element"] = {"cloud": "cloud point", "skeletal": "skeletal point", "curve": "curve vertex"}[layer_name]
            info["xyz"] = tuple(float(v) for v in layer.points[index])
            if layer_name == "curve" and layer.curve is not None:
                info["degree"] = int(layer.curve.degrees()[index])
        branch = self.branch_of(layer_name, location, index)
        if branch is not None:
            from .defects import branch_details

            info["branch"] = branch_details(self.evaluation, branch, self.beta_star)
        values = {}
        for name, q in layer.quantities.items():
            if q.location == location or (location in ("points", "vertices") and q.location in ("points", "vertices")):
                values[name] = float(q.values[index])
        info["values"] = values
        return info

    def branch_of(self, layer_name: str, location: str, index: int) -> int | None:
        """The curve branch a curve vertex or sample lies on (a click on the curve selects its
        branch); None for a junction vertex, another layer, or before an evaluation with diagnostics."""
        ev = self.evaluation
        diag = None if ev is None else getattr(ev, "diagnostics", None)
        if layer_name != "curve" or diag is None or getattr(ev, "curve", None) is None:
            return None
        key = {"vertices": "curve_vertex_branch", "samples": "curve_sample_branch"}.get(location)
        arr = diag.arrays.get(key) if key else None
        if arr is None or not 0 <= index < len(arr) or arr[index] < 0:
            return None
        return int(arr[index])


def _without_column(ev: Any, name: str) -> Any:
    """``ev`` without the column of the closed skeleton layer ``name`` (and what was computed from
    it: coverage, the reference comparison, its warnings), or None when nothing of it stays valid."""
    from dataclasses import replace

    from skelcore.diagnostics.trust import DEFECT_CODES

    if ev is None or name not in ("skeletal", "curve"):
        return None
    other = "curve" if name == "skeletal" else "skeletal"
    if getattr(ev, other) is None or (ev.skeletal is not None and getattr(ev.skeletal, "source", "") == "curve"):
        return None
    what = "skeletal point set" if name == "skeletal" else "curve skeleton"
    warnings = [w for w in ev.warnings if what not in w.message and not (name == "curve" and w.code == "trivial_smoothness")
                and not (name == "skeletal" and w.code == "no_correspondence")]
    inputs = {k: v for k, v in ev.inputs.items() if k != name and not (name == "skeletal" and k == "skeletal_index")}
    if name == "curve":
        return replace(ev, curve=None, coverage_curve=None, reference=None, warnings=warnings, inputs=inputs)
    return replace(ev, skeletal=None, topology=None, coverage_skeletal=None, correspondence=None, warnings=warnings,
                   inputs=inputs, not_computed={k: v for k, v in ev.not_computed.items() if k == "coverage" or k in DEFECT_CODES})


def _points(points: object) -> np.ndarray:
    arr = np.asarray(points, dtype=float)
    if arr.ndim != 2 or arr.shape[1] != 3:
        raise ValueError(f"expected an N x 3 array of points, got shape {arr.shape}")
    return arr
