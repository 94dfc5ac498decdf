"""The repaired skeletal set (docs/repair.md "The repaired skeletal set"), one row per cloud row.
Given a skeletal set S, row i stays S_i unless the repair removed or moved the part of the curve
nearest to S_i; then it goes to its nearest point on the repaired curve. Without S, every cloud
point's nearest point on the repaired curve (``evaluate``'s reverse correspondence for a bare curve).
Either way ``evaluate(cloud, skeletal=S2, curve=C2)`` scores the repaired pair."""

from __future__ import annotations

import numpy as np

from ..correspondence import project_onto_curve
from ..curve import CurveSkeleton

__all__ = ["repaired_skeletal"]


def repaired_skeletal(cloud: np.ndarray, before: CurveSkeleton, after: CurveSkeleton,
                      skeletal: np.ndarray | None = None) -> tuple[np.ndarray, int]:
    """(S2, number of rows moved): see the module; a part counts as changed when the point of the
    input curve nearest to S_i lies off the repaired curve by more than 1e-9 x the curve's extent."""
    if skeletal is None:
        cloud = np.asarray(cloud, float)
        return project_onto_curve(cloud, after)[0], len(cloud)
    s = np.asarray(skeletal, float)
    q = project_onto_curve(s, before)[0]
    on_after = project_onto_curve(q, after)[0]
    extent = float(np.linalg.norm(np.ptp(np.vstack([before.vertices, after.vertices]), axis=0))) or 1.0
    moved = np.linalg.norm(on_after - q, axis=1) > 1e-9 * extent
    out = s.copy()
    if moved.any():
        out[moved] = project_onto_curve(s[moved], after)[0]
    return out, int(moved.sum())
