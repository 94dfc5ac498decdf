"""Level of detail while the camera moves: big layers swap in a subsampled twin between a mouse
press and its release (and for a moment after each wheel step), so a frame under software GL stays
short; the full-detail frame follows once the camera rests.

Measured under Xvfb with software GL (frames of a 1M-point cloud while rotating; docs/guide/viewer.md).
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from PySide6 import QtCore

__all__ = ["LOD_POINTS", "lod_indices", "MotionFilter", "WHEEL_REST_MS"]

LOD_POINTS = 80_000
"""Layers larger than this get a twin of this many points (a spread, seeded random subsample)."""
WHEEL_REST_MS = 250
"""The camera counts as resting this long after the last wheel step."""


def lod_indices(n: int, keep: int = LOD_POINTS) -> np.ndarray:
    """Sorted indices of ``keep`` of ``n`` points, the same on every run (seeded)."""
    if n <= keep:
        return np.arange(n)
    return np.sort(np.random.default_rng(0).choice(n, size=keep, replace=False))


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
