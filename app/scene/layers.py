"""Layers and their scalar quantities: the data each structure of the scene carries.

A layer (the cloud, the skeletal point set, the curve skeleton) owns its local metrics as named
scalar quantities, after Polyscope's structures/quantities; NaN stays NaN (the view draws it
magenta, docs/metrics.md 5.5). Also the names every other module agrees on: the metrics, the layer order and
where each metric lives on the curve.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from skelcore.curve import CurveSkeleton
from skelcore.scores import LOCAL_METRICS

__all__ = ["METRICS", "LAYER_ORDER", "CURVE_LOCATION", "ScalarQuantity", "Layer"]

METRICS = LOCAL_METRICS
"""Local metrics the viewer can colour by (docs/metrics.md 2-4)."""

LAYER_ORDER = ("cloud", "skeletal", "curve")

# Where each metric lives on the curve skeleton: per sample (docs/metrics.md 2-3) or per vertex (docs/metrics.md 4).
CURVE_LOCATION = {"boundedness": "samples", "centeredness": "samples", "smoothness": "vertices"}


@dataclass
class ScalarQuantity:
    """Values of one local metric on one set of elements of a layer (NaN = invalid)."""

    name: str
    values: np.ndarray
    location: str  # "points" (cloud / skeletal), "vertices" or "samples" (curve)

    @property
    def n_invalid(self) -> int:
        return int(np.count_nonzero(~np.isfinite(self.values)))

    def finite_range(self) -> tuple[float, float] | None:
        """Min and max over finite values only (Polyscope's robust range), None if there are none."""
        finite = self.values[np.isfinite(self.values)]
        if finite.size == 0:
            return None
        return float(finite.min()), float(finite.max())


@dataclass
class Layer:
    """One structure of the scene.

    ``points`` are the layer's elements in user units: cloud points, skeletal points, or curve
    vertices; a curve also has ``edges`` and, once evaluated, the curve ``samples``. A skeletal set
    with another point count than the cloud may carry its ``index`` (one cloud row per skeletal
    point, docs/metrics.md 5.1) and the file it came from. ``mapping`` is the ``(scale, offset)`` a skeleton layer
    was mapped by into the cloud's frame (its file holds the unmapped coordinates). ``edited``: a curve
changed by the viewer's edits (:mod:`skelscope.edit_controller`); ``path`` stays the file it came from.
    """

    name: str
    points: np.ndarray
    path: str | None = None
    edges: np.ndarray | None = None
    curve: CurveSkeleton | None = None
    samples: np.ndarray | None = None
    sample_edge: np.ndarray | None = None
    sample_t: np.ndarray | None = None
    visible: bool = True
    point_size: float = 4.0
    opacity: float = 1.0
    quantities: dict[str, ScalarQuantity] = field(default_factory=dict)
    index: np.ndarray | None = None
    index_path: str | None = None
    mapping: tuple[float, tuple[float, float, float]] | None = None
    edited: bool = False  # a curve changed by edits since it was loaded (its file holds the curve before them)

    @property
    def n_points(self) -> int:
        return int(len(self.points))

    def _size_of(self, location: str) -> int:
        if location in ("points", "vertices"):
            return self.n_points
        if location == "samples":
            return 0 if self.samples is None else int(len(self.samples))
        raise ValueError(f"unknown location {location!r}: use 'points', 'vertices' or 'samples'")

    def add_scalar_quantity(self, name: str, values: object, *, location: str = "points") -> ScalarQuantity:
        """Attach (or replace) a named quantity; its length must match the elements it lives on."""
        arr = np.asarray(values, dtype=float).ravel()
        expected = self._size_of(location)
        if arr.size != expected:
            raise ValueError(f"quantity {name!r} has {arr.size} values but layer {self.name!r} has {expected} {location}")
        q = ScalarQuantity(name=name, values=arr, location=location)
        self.quantities[name] = q
        return q

    def quantity(self, metric: str) -> ScalarQuantity | None:
        return self.quantities.get(metric)
