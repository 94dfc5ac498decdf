"""Which role a loaded file plays (cloud, skeletal point set, curve skeleton): Qt-free rules.

Issue 3's rules for files dropped or named together: a file with edges is a curve skeleton; a point
set with the cloud's point count is a skeletal point set (SPEC 0's pointwise correspondence); the first
point set is the cloud. When that is ambiguous the ``ask`` callback decides (the window shows a dialog).
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from typing import Any, Callable, Sequence

import numpy as np

ROLES = ("cloud", "skeletal", "curve")

Ask = Callable[[str, list[str]], "str | None"]
"""``ask(question, options) -> chosen option`` or None to skip the file."""


@dataclass(frozen=True)
class Assignment:
    role: str  # "cloud", "skeletal" or "curve"
    loaded: Any  # skelcore.io.Loaded


def _count(loaded: Any) -> int:
    return int(len(loaded.points))


def _spread(loaded: Any, max_points: int = 20000) -> float:
    """Median nearest-neighbour spacing: contraction packs points onto a curve (many coincide), so
    the cloud's spacing is the largest. Same-size sets are subsampled alike, keeping the ratio."""
    from scipy.spatial import cKDTree

    pts = np.asarray(loaded.points, dtype=float)
    if len(pts) > max_points:
        pts = pts[np.linspace(0, len(pts) - 1, max_points).astype(np.int64)]
    if len(pts) < 2:
        return 0.0
    dist, _ = cKDTree(pts).query(pts, k=2)
    return float(np.median(dist[:, 1]))


def assign_roles(items: Sequence[Any], cloud_count: int | None, ask: Ask) -> list[Assignment]:
    """Roles for ``items`` (``skelcore.io.Loaded``), given the currently loaded cloud's size.

    Several same-size point sets and no cloud yet: the cloud is the one with the clearly largest
    point spacing (a skeletal set is the cloud contracted), the first one by the issue's rule otherwise;
    when no spread stands out, ``ask``. A point set whose size differs from an already loaded cloud
    cannot be its skeletal set: ``ask`` whether it replaces the cloud.
    """
    out: list[Assignment] = [Assignment("curve", it) for it in items if it.kind == "curve"]
    points = [it for it in items if it.kind != "curve"]
    count = cloud_count
    if count is None and points:
        first = points[0]
        same = [p for p in points if _count(p) == _count(first)]
        spreads = sorted(((_spread(p), i) for i, p in enumerate(same)), reverse=True)
        if len(same) > 1 and spreads[0][0] > 1.5 * spreads[1][0]:
            cloud = same[spreads[0][1]]
        elif len(same) > 1:
            names = [os.path.basename(p.path) for p in same]
            choice = ask("Several point sets have the same number of points and similar spacing. Which one is the cloud?", names)
            cloud = same[names.index(choice)] if choice in names else first
        else:
            cloud = first
        out.append(Assignment("cloud", cloud))
        points = [p for p in points if p is not cloud]
        count = _count(cloud)
    skeletal_taken = False
    for p in points:
        name = os.path.basename(p.path)
        if _count(p) == count and not skeletal_taken:
            out.append(Assignment("skeletal", p))
            skeletal_taken = True
            continue
        if _count(p) == count:
            question = f"{name} has the cloud's {count} points, like another file dropped with it. Load it as:"
        else:
            question = (
                f"{name} has {_count(p)} points but the cloud has {count}, so it cannot be a skeletal point "
                "set (pointwise correspondence). Load it as:"
            )
        options = ["the cloud (replaces the current one)", "the skeletal point set"]
        choice = ask(question, options)
        if choice == options[0]:
            out.append(Assignment("cloud", p))
            count = _count(p)
        elif choice == options[1]:
            out.append(Assignment("skeletal", p))
            skeletal_taken = True
    order = {"cloud": 0, "skeletal": 1, "curve": 2}
    return sorted(out, key=lambda a: order[a.role])
