"""The half chords of one cloud's samples, kept so that later evaluations and an edit's updates on the
same cloud do not march them again (docs/diagnostics.md "Beside a branch", docs/performance.md 6.10).

A chord depends only on the cloud (its points), the sample row and which way the row's normal is turned
(towards the skeleton's foot, which an edit may move): the normals and each direction's chords are kept
per row, a direction marched on its first need. One cloud at a time (a different cloud, spacing or set of
rows starts afresh); a lock keeps two stages of one evaluation from marching the same chords twice.
"""

from __future__ import annotations

import threading

import numpy as np

__all__ = ["ChordCache"]


class ChordCache:
    """Per cloud row of the last cloud asked: its normal (as the principal axes give it, not turned) and
    the half chord along it (column 0) and against it (column 1), NaN where not yet marched (``done``)."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self._key: tuple | None = None
        self.normal: np.ndarray | None = None
        self.chords: np.ndarray | None = None
        self.done: np.ndarray | None = None

    def holds(self, pts: np.ndarray, rows: np.ndarray, spacing: float) -> bool:
        """Whether the kept chords are those of ``pts``' ``rows`` at ``spacing`` (call under ``lock``)."""
        if self._key is None:
            return False
        kept_pts, kept_rows, kept_spacing = self._key
        return (kept_spacing == spacing and kept_rows.shape == rows.shape and np.array_equal(kept_rows, rows)
                and (kept_pts is pts or (kept_pts.shape == pts.shape and np.array_equal(kept_pts, pts))))

    def start(self, pts: np.ndarray, rows: np.ndarray, spacing: float, normal: np.ndarray) -> None:
        """Keep ``normal`` for ``pts``' ``rows`` at ``spacing``, no chord marched yet (call under ``lock``)."""
        self._key = (pts, rows.copy(), float(spacing))
        self.normal = normal
        self.chords = np.full((len(rows), 2), np.nan)
        self.done = np.zeros((len(rows), 2), bool)
