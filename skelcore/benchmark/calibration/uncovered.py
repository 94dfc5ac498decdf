"""How much of a reference a skeleton leaves uncovered (length in local radii, the cloud's surface
around it), and a neuron's removed branch the cloud can show missing: the size the calibration's
truth and its removal share (docs/benchmark.md "The calibration's truth on a neuron")."""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np
from scipy.spatial import cKDTree

from ..skeleton_defects import _drop_isolated, _terminal_branches, drop_vertices

__all__ = ["MISS_AREA", "uncovered_radii", "uncovered_area", "visible_removal"]

#: on a neuron, ``incomplete`` is true only when the uncovered part also holds this much of the
#: cloud's surface (squared median local radii: a tube about 6 radii long); smaller: left out
MISS_AREA = 36.0


def _samples(v: np.ndarray, e: np.ndarray, step: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Points along each edge at most ``step`` (per edge) apart, and their edge."""
    length = np.linalg.norm(v[e[:, 1]] - v[e[:, 0]], axis=1)
    n = np.clip(np.ceil(length / np.maximum(step, 1e-12)).astype(int), 1, 400)
    edge = np.repeat(np.arange(len(e)), n + 1)
    t = np.concatenate([np.linspace(0.0, 1.0, k + 1) for k in n])
    pts = v[e[edge, 0]] + t[:, None] * (v[e[edge, 1]] - v[e[edge, 0]])
    return pts, edge


def _radius_at(points: np.ndarray, w: Any) -> np.ndarray:
    return w.ref[2][cKDTree(w.ref[0]).query(points)[1]]


def _uncovered(made: Any, w: Any) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """The reference's samples, their length weight, local radius and whether each is uncovered."""
    rv, re, rr = w.ref
    ref_pts, edge = _samples(rv, re, 0.5 * np.minimum(rr[re[:, 0]], rr[re[:, 1]]))
    seg = np.linalg.norm(rv[re[:, 1]] - rv[re[:, 0]], axis=1)
    per_edge = np.bincount(edge, minlength=len(re))
    weight = seg[edge] / np.maximum(per_edge[edge], 1)
    near = cKDTree(rv).query(ref_pts)[1]
    r = rr[near]
    r_made = _radius_at(made.vertices, w)
    pts, _ = _samples(made.vertices, made.edges, 0.25 * np.minimum(r_made[made.edges[:, 0]], r_made[made.edges[:, 1]]))
    if not len(pts):
        pts = made.vertices
    d = cKDTree(pts).query(ref_pts)[0]
    far = d > 2.0 * r
    if w.facts is not None:
        far &= np.asarray(w.facts.outside_radii)[near] <= 1.0
    return ref_pts, weight, r, far


def uncovered_radii(made: Any, w: Any) -> float:
    """The reference's length (in its local radii) farther than two local radii from the skeleton;
    on a neuron only along nodes inside the mesh or within one radius of it (the cloud shows them)."""
    _, weight, r, far = _uncovered(made, w)
    return float(np.sum(weight[far] / r[far]))


def uncovered_area(made: Any, w: Any) -> float:
    """The cloud's surface around the uncovered reference (its points nearest to an uncovered sample,
    x the median spacing squared), in squared median local radii of the cloud: how much of the shape
    the missing part is, whatever the density."""
    ref_pts, _, _, far = _uncovered(made, w)
    ok = np.isfinite(w.local_radius)
    cloud = w.cloud[ok]
    if not far.any() or len(cloud) < 2:
        return 0.0
    owner = cKDTree(ref_pts).query(cloud)[1]
    spacing = float(np.median(cKDTree(cloud).query(cloud, k=2)[0][:, 1]))
    return float(np.count_nonzero(far[owner]) * spacing ** 2 / np.median(w.local_radius[ok]) ** 2)



def visible_removal(w: Any, rng: np.random.Generator, tries: int = 30) -> tuple[np.ndarray, np.ndarray] | None:
    """One terminal branch of a neuron's reference removed whole whose uncovered part holds at least
    ``MISS_AREA`` (:func:`uncovered_area`): drawn in random order among those whose traced tube has
    that surface, at most ``tries`` measured; None when none does."""
    v, e, r = (np.asarray(x) for x in w.ref)
    v, e, r = v.astype(float), e.astype(np.int64), r.astype(float)
    deg = np.bincount(e.ravel(), minlength=len(v))
    branches = _terminal_branches(v, e)
    if not (deg >= 3).any() or len(branches) < 2:
        return None
    need = MISS_AREA * float(np.nanmedian(np.asarray(w.local_radius, float))) ** 2
    tube = np.array([2 * np.pi * float(np.mean(r[path])) * length for _end, path, length in branches])
    for i in rng.permutation(np.flatnonzero(tube >= need))[:tries]:
        drop = np.zeros(len(v), bool)
        drop[branches[i][1]] = True
        got = _drop_isolated(*drop_vertices(v, e, drop))
        if uncovered_area(SimpleNamespace(vertices=got[0], edges=got[1]), w) >= MISS_AREA:
            return got
    return None
