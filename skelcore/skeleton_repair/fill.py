"""Candidate actions for a missing part (docs/repair.md "Missing parts"): the unexplained cloud
region becomes a new stretch of curve attached at the nearest vertex: the centroids of the
region's slabs along its main axis (a tube's end seen all around: the slab centroids lie on its axis)
the region skeletonized by :func:`skelcore.skeletonize` (``skelscope``), or the region's axis curve
at its own spacing (:mod:`skelcore.skeleton.local_axis`: a thin branch). Tried last, and made one at
a time (:func:`fill_actions`), each when its try is reached (:class:`Fills`; docs/repair.md "The
repair's cost")."""

from __future__ import annotations

import hashlib
from contextlib import AbstractContextManager, nullcontext
from typing import Any, Callable, Iterator

import numpy as np
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from .all_round import all_round_share
from .proposals import Action
from .thin_region import thinned

__all__ = ["fill_missing", "fill_actions", "Fills", "WHEN_REACHED"]

#: whether a round makes a fill only when its try is reached (:class:`Fills`): True; False makes every
#: fill a round may try before the first try, the slower path, the same tries, log and curve
#: (tests/engine/test_repair_trial.py)
WHEN_REACHED = True

#: whether a region seen all round (its share of its cross-sections at least ``all_round``,
#: :mod:`.all_round`) has its slabs' centroids tried before its axis curve
SLABS_FIRST = True


def _slab_line(pts: np.ndarray, step: float) -> np.ndarray:
    """Centroids of slabs ``step`` wide across the region's main axis, in order along it."""
    c = pts.mean(axis=0)
    axis = np.linalg.svd(pts - c, full_matrices=False)[2][0]
    t = (pts - c) @ axis
    k = np.floor((t - t.min()) / step).astype(np.int64)
    out = [pts[k == i].mean(axis=0) for i in np.unique(k) if np.count_nonzero(k == i) >= 3]
    return np.array(out).reshape(-1, 3)


def _attach_polyline(curve: CurveSkeleton, line: np.ndarray) -> tuple[list[dict[str, Any]], int] | None:
    used = np.flatnonzero(np.bincount(curve.edges.ravel(), minlength=curve.n_vertices) > 0)
    d, j = cKDTree(curve.vertices[used]).query(line[[0, -1]])
    if d[1] < d[0]:
        line, d, j = line[::-1], d[::-1], j[::-1]
    line = line[1:]  # the slab at the curve holds the junction's surface too: off the axis
    j0 = int(cKDTree(curve.vertices[used]).query(line[0])[1])
    j = (j0, j[1])
    prev, n, out = int(used[j[0]]), curve.n_vertices, []
    for i, p in enumerate(line):
        out.append({"op": "add_vertex", "args": {"position": [float(x) for x in p], "attach_to": prev}})
        prev = n + i
    return out, int(used[j[0]])


def _part_entries(curve: CurveSkeleton, part: CurveSkeleton) -> tuple[list[dict[str, Any]], int] | None:
    """The edit-log entries adding ``part`` (its vertices on edges, its edges), attached by its vertex
    nearest the curve to that vertex of the curve."""
    if part.n_edges == 0:
        return None
    used = np.flatnonzero(np.bincount(curve.edges.ravel(), minlength=curve.n_vertices) > 0)
    keep = np.flatnonzero(np.bincount(part.edges.ravel(), minlength=part.n_vertices) > 0)
    d, j = cKDTree(curve.vertices[used]).query(part.vertices[keep])
    first = int(np.argmin(d))
    n = curve.n_vertices
    at = int(used[j[first]])
    new_id = np.full(part.n_vertices, -1, np.int64)
    new_id[keep] = n + np.arange(len(keep))
    out = [{"op": "add_vertex", "args": {"position": p, "attach_to": at if i == first else None}}
           for i, p in enumerate(part.vertices[keep].tolist())]  # the same Python floats and ints, in bulk
    out += [{"op": "add_edge", "args": {"edge": e}} for e in np.sort(new_id[part.edges], axis=1).tolist()]
    return out, at


def _made(memo: dict | None, how: str, pts: np.ndarray, make: Callable[[], CurveSkeleton | None]
          ) -> CurveSkeleton | None:
    """``make()``, kept in ``memo`` by ``how`` and the region's points: a region a kept fill left as
    it was gives the same curve in the next round, made once."""
    if memo is None:
        return make()
    key = (how, pts.shape, hashlib.sha1(np.ascontiguousarray(pts).tobytes()).hexdigest())
    if key not in memo:
        memo[key] = make()
    return memo[key]


def _skeleton_entries(curve: CurveSkeleton, pts: np.ndarray, memo: dict | None = None,
                      fill_points: int | None = None) -> tuple[list[dict[str, Any]], int] | None:
    """The region's ``skelscope`` curve, on at most ``fill_points`` points (:mod:`.thin_region`; None:
    all of them)."""
    from ..skeleton import skeletonize

    def make() -> CurveSkeleton | None:
        try:
            return skeletonize(pts if fill_points is None else thinned(pts, fill_points), method="skelscope")[1]
        except (SkelInputError, ValueError, np.linalg.LinAlgError, RuntimeError):
            return None

    part = _made(memo, "skeleton", pts, make)
    return None if part is None else _part_entries(curve, part)


def _axis_entries(curve: CurveSkeleton, pts: np.ndarray, memo: dict | None = None
                  ) -> tuple[list[dict[str, Any]], int] | None:
    """The region's axis curve at its own spacing (:mod:`skelcore.skeleton.local_axis`), its largest
    piece: a thin missing branch, which the whole-region skeletonizers reduce to a few vertices."""
    from ..skeleton.local_axis import axis_contract, axis_curve
    from ..skeleton.skeleton_params import AxisParams
    from .proposals import component_labels

    if len(pts) < 20:
        return None

    def make() -> CurveSkeleton | None:
        part = axis_curve(axis_contract(pts), AxisParams(curve="balls"))
        if part.n_edges == 0:
            return None
        _, label = component_labels(part)
        big = np.bincount(label[part.edges[:, 0]]).argmax()
        return CurveSkeleton.from_raw(part.vertices, part.edges[label[part.edges[:, 0]] == big])

    part = _made(memo, "axis", pts, make)
    return None if part is None else _part_entries(curve, part)


def fill_missing(curve: CurveSkeleton, missing: Any, cloud: np.ndarray, max_regions: int = 2,
                 memo: dict | None = None, fill_points: int | None = None) -> list[Action]:
    """Up to three actions per counted missing region (largest first) of ``missing``
    (:class:`~skelcore.diagnostics.missing_parts.MissingParts` of the evaluated ``cloud``)."""
    return list(fill_actions(curve, missing, cloud, max_regions, memo, fill_points=fill_points))


def fill_actions(curve: CurveSkeleton, missing: Any, cloud: np.ndarray, max_regions: int = 2,
                 memo: dict | None = None, all_round: float = np.inf, fill_points: int | None = None
                 ) -> Iterator[Action]:
    """:func:`fill_missing`'s actions one at a time, in its order: each is made (a region's axis curve,
    its skeletonization) only when asked for. Every region's axis curve first, then every region's
    skeleton, then the slabs' centroids: on the tuning neurons the axis curve raised GT F1 most and
    added no cycle, the slabs' few centroids of a large region lowered it (docs/repair.md "Fills that
    pass"), and one region refused leaves the next one its try. A region seen all round (the share of
    its cross-sections it holds, :mod:`.all_round`, at least ``all_round``: a tube's end, a thick part
    cut off, a whole missing branch) has its slabs' centroids tried before its axis curve: its axis
    lies inside it, where the slabs' centroids are, while the axis curve of a thick part is a tangle on
    its surface (docs/repair.md "A thick part's fill"). ``memo``: the regions' curves made in the
    rounds before (:func:`_made`); ``fill_points``: a region's skeletonization runs on at most this
    many points (:mod:`.thin_region`; None: all)."""
    if missing is None or not missing.counted or len(missing.region) != len(cloud):
        return
    e = curve.edges
    step = float(np.median(np.linalg.norm(curve.vertices[e[:, 0]] - curve.vertices[e[:, 1]], axis=1)))
    regions = [(reg, cloud[missing.region == reg.id]) for reg in missing.counted[:max_regions]]
    regions = [(reg, pts) for reg, pts in regions if len(pts) >= 10]
    whole = {reg.id: all_round_share(cloud, missing.region == reg.id, max(step, 1e-12)) for reg, _ in regions}

    def target(reg: Any) -> dict[str, Any]:
        share = whole[reg.id]
        return {"region": int(reg.id), "all_round": None if share is None else round(share, 4)}

    def slabs(reg: Any, pts: np.ndarray) -> Iterator[Action]:
        line = _slab_line(pts, max(step, 1e-12))
        if len(line) >= 3:
            entries, at = _attach_polyline(curve, line)
            yield Action("incomplete", target(reg), f"missing region {reg.id} ({reg.n_points} points): "
                         f"the centroids of its slabs ({len(line)}) attached at vertex {at}", entries)

    first = {reg.id for reg, _ in regions if SLABS_FIRST and (whole[reg.id] or 0.0) >= all_round}
    for reg, pts in regions:
        if reg.id in first:
            yield from slabs(reg, pts)
        made = _axis_entries(curve, pts, memo)
        if made is not None:
            entries, at = made
            yield Action("incomplete", target(reg), f"missing region {reg.id} ({reg.n_points} points): "
                         f"its axis curve at its own spacing attached at vertex {at}", entries)
    for reg, pts in regions:
        made = _skeleton_entries(curve, pts, memo, fill_points)
        if made is not None:
            entries, at = made
            yield Action("incomplete", target(reg), f"missing region {reg.id} ({reg.n_points} points) "
                         f"skeletonized and attached at vertex {at}", entries)
    for reg, pts in regions:
        if reg.id not in first:
            yield from slabs(reg, pts)


class Fills:
    """A round's fills (:func:`fill_actions`, at most ``cap``), each made when first asked for: the
    round tries them after its other candidates and stops at the first action kept, so the fills
    behind a kept one (the axis curves and skeletons of the regions it did not reach) are not made
    that round (docs/repair.md "The repair's cost"). The actions and their order are those of the
    whole list; ``timer()``: the context each making runs in (the repair's phase clock)."""

    def __init__(self, actions: Iterator[Action], cap: int,
                 timer: Callable[[], AbstractContextManager] = nullcontext) -> None:
        self._next, self.cap, self._timer = actions, cap, timer
        self.made: list[Action] = []
        if not WHEN_REACHED:
            self.first(cap)

    def _more(self) -> bool:
        with self._timer():
            a = next(self._next, None)
        if a is None:
            self.cap = len(self.made)
            return False
        self.made.append(a)
        return True

    def first(self, k: int) -> list[Action]:
        """The first ``k`` fills (fewer when there are fewer), made now."""
        while len(self.made) < min(k, self.cap) and self._more():
            pass
        return self.made[:max(k, 0)]

    def after(self, k: int) -> Iterator[Action]:
        """The fills after the first ``k``, each made when reached."""
        i = k
        while i < self.cap and (i < len(self.made) or self._more()):
            yield self.made[i]
            i += 1
