"""Level of detail while the camera moves: big layers swap in a subsampled twin between a mouse
press and its release (and for a moment after each wheel step), so a frame under software GL stays
short; the full-detail frame follows once the camera rests.

Both the layer and its twin stay built (their arrays uploaded once); a swap only toggles visibility.
A twin's points are in a seeded random order, so its first ``k`` points are a spread subsample of any
size: the twin draws the first ``DetailLevel.points`` of them, a count set from the measured time of
the frames drawn while moving (docs/performance.md section 5).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from PySide6 import QtCore

__all__ = ["LOD_POINTS", "LOD_LADDER", "FRAME_BUDGET_S", "lod_indices", "lod_order", "DetailLevel",
           "MotionFilter", "WHEEL_REST_MS"]

LOD_POINTS = 80_000
"""Layers larger than this get a twin of this many points (a spread, seeded random subsample)."""
LOD_LADDER = (80_000, 40_000, 20_000, 10_000, 5_000, 2_500)
"""The twins' point counts, largest first: each step halves the points a moving frame draws."""
FRAME_BUDGET_S = 0.060
"""A frame drawn while moving should take at most this long (about 15 frames a second)."""
WHEEL_REST_MS = 250
"""The camera counts as resting this long after the last wheel step."""


def lod_indices(n: int, keep: int = LOD_POINTS) -> np.ndarray:
    """Sorted indices of ``keep`` of ``n`` points, the same on every run (seeded)."""
    if n <= keep:
        return np.arange(n)
    return np.sort(np.random.default_rng(0).choice(n, size=keep, replace=False))


def lod_order(n: int, keep: int = LOD_POINTS) -> np.ndarray:
    """Indices of ``keep`` of ``n`` points in a seeded random order: every prefix is a spread subsample."""
    rng = np.random.default_rng(0)
    return rng.permutation(n)[:keep] if n <= 4 * keep else rng.choice(n, size=keep, replace=False)


class DetailLevel:
    """The twins' point count, chosen from measured frame times: the first drag over new data starts
    from the last full-detail frame's cost a point (:meth:`fit`); then a frame drawn while moving over
    FRAME_BUDGET_S steps down the ladder as far as its excess asks, one well under it (a third) steps
    up one. The count is kept between drags: the next drag starts where this one ended."""

    def __init__(self, ladder: tuple[int, ...] = LOD_LADDER, budget_s: float = FRAME_BUDGET_S) -> None:
        self.ladder = tuple(ladder)
        self.budget_s = budget_s
        self.step = 0

    @property
    def points(self) -> int:
        return self.ladder[self.step]

    def fit(self, seconds: float, points: int, twins: int) -> None:
        """Start from a full-detail frame of ``points`` points that took ``seconds``: the largest count
        whose ``twins`` twins would be drawn within the budget at that cost a point."""
        if points <= 0 or seconds <= 0 or twins <= 0:
            return
        per_point = seconds / points
        fits = [i for i, n in enumerate(self.ladder) if n * twins * per_point <= self.budget_s]
        self.step = fits[0] if fits else len(self.ladder) - 1

    def frame_took(self, seconds: float) -> bool:
        """Account for a moving frame of ``seconds``; True when the count changed."""
        step = self.step
        if seconds > self.budget_s:
            halvings = int(np.ceil(np.log2(seconds / self.budget_s)))
            self.step = min(self.step + max(halvings, 1), len(self.ladder) - 1)
        elif seconds < self.budget_s / 3 and self.step > 0:
            self.step -= 1
        return self.step != step


class MotionFilter(QtCore.QObject):
    """Reports ``on_motion(True)`` when a camera move starts (a mouse button pressed on the view, a
    wheel step) and ``on_motion(False)`` when it ends (release; WHEEL_REST_MS after the last step)."""

    def __init__(self, on_motion: Callable[[bool], None]) -> None:
        super().__init__()
        self._on_motion = on_motion
        self._buttons = 0
        self._wheel = QtCore.QTimer(self)
        self._wheel.setSingleShot(True)
        self._wheel.setInterval(WHEEL_REST_MS)
        self._wheel.timeout.connect(self._rest)

    def eventFilter(self, obj: QtCore.QObject, event: QtCore.QEvent) -> bool:  # noqa: N802
        t = event.type()
        if t == QtCore.QEvent.Type.MouseButtonPress:
            self._buttons += 1
            self._on_motion(True)
        elif t == QtCore.QEvent.Type.MouseButtonRelease:
            self._buttons = max(self._buttons - 1, 0)
            if not self._buttons:
                self._rest()
        elif t == QtCore.QEvent.Type.Wheel:
            self._on_motion(True)
            self._wheel.start()
        return False

    def _rest(self) -> None:
        if not self._buttons and not self._wheel.isActive():
            self._on_motion(False)
