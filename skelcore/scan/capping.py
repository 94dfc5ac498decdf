"""``--cap-openings``: close small flat openings the paper's way (docs/metrics.md 6.2).

The paper capped its cave "to ensure a closed shape" before scoring boundedness.  Each opening found
by :func:`skelcore.scan.openings.find_openings` is capped with its flat fill (points on the rim's
fitted plane, at the rim's spacing, where the surface is missing), unless

- its rim is not flat: RMS distance from its plane above ``cap_flatness`` x its radius (a missing
  side of a one-sided scan is not closed by a plane: give the viewpoint instead), or
- the cap would add more than ``cap_max_share`` of the cloud's points (a cap that large would be
  a guess at most of the shape).

The caps enter boundedness only: topology and centeredness keep the cloud's own points (a skeletal set
in pointwise correspondence has no rows for them, and a cap in a cross-section would pull the
centeredness ring), coverage measures the cloud as scanned.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from ..params import Params
from .openings import Opening

__all__ = ["Caps", "cap_openings"]


@dataclass
class Caps:
    """The caps decided for a list of openings: the points added and, per opening, capped or why not."""

    points: np.ndarray  # (m, 3) every cap's points, in the openings' units
    capped: list[int] = field(default_factory=list)  # indices into the openings list
    refused: dict[int, str] = field(default_factory=dict)  # index -> one line saying why


def cap_openings(openings: list[Opening], n_points: int, params: Params = Params()) -> Caps:
    """Cap every small, flat opening (module docstring); ``n_points`` is the cloud's size.

    Examples
    --------
    >>> from skelcore.shapes import cylinder
    >>> from skelcore.scan.openings import find_openings
    >>> tube = cylinder(4000, capped=False).cloud
    >>> caps = cap_openings(find_openings(tube), len(tube))
    >>> caps.capped, caps.refused
    ([0, 1], {})
    """
    parts, capped, refused = [], [], {}
    limit = float(params.cap_max_share) * n_points
    for i, o in enumerate(openings):
        if o.flatness > params.cap_flatness:
            refused[i] = (f"not flat: its rim lies {o.flatness:.2f} x its radius from its plane (RMS; cap_flatness = "
                          f"{params.cap_flatness:g}); a missing side is scored with --viewpoint, not capped")
        elif len(o.fill) > limit:
            refused[i] = (f"too large: the cap would add {len(o.fill)} points, {len(o.fill) / n_points:.1%} of the "
                          f"cloud (cap_max_share = {params.cap_max_share:g})")
        else:
            parts.append(o.fill)
            capped.append(i)
    points = np.vstack(parts) if parts else np.empty((0, 3))
    return Caps(points, capped, refused)
