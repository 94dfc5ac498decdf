"""Which role a loaded file plays (cloud, skeletal point set, curve skeleton): Qt-free rules.

The rules for files dropped or named together: a file with edges is a curve skeleton; a point
set with the cloud's point count is a skeletal point set (the pointwise correspondence of docs/metrics.md 0); the first
point set is the cloud; a complete set dropped at once is assigned within itself. When that is
ambiguous the ``ask`` callback decides (the window shows a dialog) and its default never replaces
the loaded cloud. A point set with another count than the loaded cloud may also be a skeletal set
scored by reverse projection or through an index file (docs/metrics.md 5.1); replacing the cloud under a
loaded skeleton says in the same answer whether the skeleton stays, so nothing is asked twice.
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
    """``correspondence`` of a skeletal set: None (pointwise or none), "reverse" or "index" (an index
    file is still to be chosen); ``keep_skeleton`` of a cloud replacing the loaded one: the answer
    already given (None: not asked yet)."""

    role: str  # "cloud", "skeletal" or "curve"
    loaded: Any  # skelcore.io.Loaded
    correspondence: str | None = None
    keep_skeleton: bool | None = None


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


SKIP = "skip this file"
REPLACE_CLOUD = "the cloud (replaces the loaded cloud and clears its skeleton)"
REPLACE_CLOUD_ONLY = "the cloud (replaces the loaded cloud)"
REPLACE_CLOUD_KEEP = "the cloud (replaces the loaded cloud, keeps its skeleton)"
SKELETAL = "the skeletal point set"
SKELETAL_REVERSE = "skeletal set (no correspondence: reverse projection)"
SKELETAL_INDEX = "skeletal set with an index file…"


def _fresh_cloud(points: list[Any], ask: Ask) -> Any:
    """The cloud among point sets dropped together on a window without a cloud (or as a complete
    set): of a group of same-size sets, the one with the clearly largest point spacing (a skeletal
    set is the cloud contracted); ``ask`` when no spread stands out; otherwise the first."""
    counts = [_count(p) for p in points]
    group_count = next((c for c in counts if counts.count(c) > 1), None)
    if group_count is None:
        return points[0]
    same = [p for p in points if _count(p) == group_count]
    spreads = sorted(((_spread(p), i) for i, p in enumerate(same)), reverse=True)
    if spreads[0][0] > 1.5 * spreads[1][0]:
        return same[spreads[0][1]]
    names = [os.path.basename(p.path) for p in same]
    choice = ask("Several point sets have the same number of points and similar spacing. Which one is the cloud?", names)
    return same[names.index(choice)] if choice in names else same[0]


def is_complete_set(items: Sequence[Any], cloud_count: int | None) -> bool:
    """A drop that brings its own cloud: two same-size point sets (a cloud and its skeletal set), or
    one point set that cannot be the loaded cloud's skeletal set, dropped with a curve skeleton."""
    points = [it for it in items if it.kind != "curve"]
    counts = [_count(p) for p in points]
    if any(counts.count(c) > 1 for c in counts):
        return True
    has_curve = len(points) < len(items)
    return has_curve and len(points) == 1 and cloud_count is not None and counts[0] != cloud_count


def assign_roles(items: Sequence[Any], cloud_count: int | None, ask: Ask,
                 skeleton_loaded: bool = False) -> list[Assignment]:
    """Roles for ``items`` (``skelcore.io.Loaded``), given the currently loaded cloud's size and
    whether a skeleton is loaded over it.

    No cloud yet, or a complete set (:func:`is_complete_set`): the set is assigned within itself
    (:func:`_fresh_cloud`), never against the loaded cloud. Otherwise a point set with the loaded
    cloud's size is its skeletal set; any other point set is asked about: a skeletal set by reverse
    projection or with an index file, or the cloud (keeping or clearing a loaded skeleton). The
    question's first (default) answer skips the file: an ambiguous drop never replaces the loaded
    cloud by default.
    """
    out: list[Assignment] = [Assignment("curve", it) for it in items if it.kind == "curve"]
    points = [it for it in items if it.kind != "curve"]
    count = cloud_count
    if points and (count is None or is_complete_set(items, cloud_count)):
        cloud = _fresh_cloud(points, ask)
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
        over_skeleton = skeleton_loaded and not any(a.role == "cloud" for a in out)
        clouds = [REPLACE_CLOUD, REPLACE_CLOUD_KEEP] if over_skeleton else [REPLACE_CLOUD_ONLY]
        if _count(p) == count:
            question = f"{name} has the cloud's {count} points, like another file dropped with it. Load it as:"
            options = [SKIP, SKELETAL, *clouds]
        else:
            question = (
                f"{name} has {_count(p)} points but the cloud has {count}: it is not a skeletal point set in "
                "row-by-row (pointwise) correspondence with the cloud. Load it as:"
            )
            options = [SKIP, SKELETAL_REVERSE, SKELETAL_INDEX, *clouds]
        choice = ask(question, options)
        if choice in (REPLACE_CLOUD, REPLACE_CLOUD_ONLY, REPLACE_CLOUD_KEEP):
            out = [a for a in out if a.role != "cloud"]
            out.append(Assignment("cloud", p, keep_skeleton=choice == REPLACE_CLOUD_KEEP))
            count = _count(p)
        elif choice in (SKELETAL, SKELETAL_REVERSE, SKELETAL_INDEX):
            out = [a for a in out if a.role != "skeletal"]
            mode = {SKELETAL_REVERSE: "reverse", SKELETAL_INDEX: "index"}.get(choice)
            out.append(Assignment("skeletal", p, correspondence=mode))
            skeletal_taken = True
    order = {"cloud": 0, "skeletal": 1, "curve": 2}
    return sorted(out, key=lambda a: order[a.role])
