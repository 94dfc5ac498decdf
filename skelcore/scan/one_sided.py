"""Thin parts seen from one side: the missing side of a one-sided scan where the parts are too thin for
the opening search (docs/metrics.md 6.1).

The rim of a one-sided scan of a neuron runs along every thin branch, where :func:`.openings.find_openings`
sets the boundary points aside as thin (its k neighbours wrap round the part in any sampling), so no
opening was found and the rays left through the missing side unseen.  What tells a half tube from a
whole one is where its points lie around the axis: from each thin boundary point's nearest skeleton
element, the mean unit direction to the cloud points within two local radii, across the axis.  On a
closed part these point every way and cancel over the cloud (the traced axes are off-centre: 0.18-0.29
of their mean length remains on the tuning neurons); seen from one side, they all point towards the
sensor (0.68-0.69).  Above ``open_one_sided`` the missing side is the visible points mirrored through
their axis elements.
"""

from __future__ import annotations

from typing import Callable

import numpy as np
from scipy.spatial import cKDTree

from ..params import Params
from .openings import Opening, median_spacing

__all__ = ["one_sided_thin", "facing"]


def facing(cloud: np.ndarray, elements: np.ndarray, near: list, skeleton: np.ndarray, skel_tree: cKDTree,
           min_points: int = 8) -> np.ndarray:
    """(len(elements), 3): the mean unit direction from each element to its cloud points ``near`` (the
    rows within its reach), across the axis (its component along the principal direction of the
    element's 8 nearest ``skeleton`` elements, ``skel_tree`` their tree, left out: a density that
    changes along a part is no side); zero where fewer than ``min_points`` points are near (too few to
    show a side)."""
    out = np.zeros((len(elements), 3))
    nb = skel_tree.query(elements, k=min(8, len(skeleton)), workers=-1)[1].reshape(len(elements), -1)
    along = skeleton[nb] - skeleton[nb].mean(axis=1, keepdims=True)
    axis = np.linalg.eigh(np.matmul(along.transpose(0, 2, 1), along))[1][:, :, 2]
    for i, rows in enumerate(near):
        if len(rows) >= min_points:
            u = cloud[rows] - elements[i]
            n = np.linalg.norm(u, axis=1, keepdims=True)
            m = np.mean(np.divide(u, n, out=np.zeros_like(u), where=n > 0), axis=0)
            out[i] = m - (m @ axis[i]) * axis[i]
    return out


def one_sided_thin(cloud: np.ndarray, skeleton: np.ndarray, thin_rows: np.ndarray, params: Params = Params(), *,
                   cloud_tree: Callable[[], cKDTree] | None = None,
                   skel_tree: cKDTree | None = None) -> Opening | None:
    """The missing side of the thin parts (module docstring) as one opening of kind "side" whose fill
    and dome are the mirrored points farther than a median spacing from the cloud; None when the thin
    boundary points are fewer than ``thin_min_share`` of the cloud or face no common way.
    ``cloud_tree`` (gives the cloud's kd-tree, built once by the caller) and ``skel_tree``: shared trees."""
    cloud = np.asarray(cloud, dtype=float)
    rows = np.unique(np.asarray(thin_rows, np.int64))
    if len(rows) < max(8, float(params.thin_min_share) * len(cloud)) or len(skeleton) == 0:
        return None
    tree = cKDTree(cloud) if cloud_tree is None else cloud_tree()
    skel_tree = cKDTree(skeleton) if skel_tree is None else skel_tree
    to_axis, which = skel_tree.query(cloud[rows], k=1, workers=-1)
    elements, first = np.unique(which, return_index=True)
    axis = skeleton[elements]
    reach = 2.0 * np.maximum(tree.query(axis, k=1, workers=-1)[0], to_axis[first])
    near = tree.query_ball_point(axis, reach, workers=-1)
    u = facing(cloud, axis, near, skeleton, skel_tree)
    length = np.linalg.norm(u, axis=1)
    if not length.any():
        return None
    judged = np.flatnonzero(length > 0)
    # one element per cell of two reaches (neighbouring elements share their points: one sample)
    cell = np.floor(axis[judged] / (2.0 * float(np.median(reach[judged])))).astype(np.int64)
    judged = judged[np.unique(cell, axis=0, return_index=True)[1]]
    common = np.linalg.norm(u[judged].mean(axis=0)) / float(length[judged].mean())
    # n random directions average to about 1 / sqrt(n) of their length: three times that is no chance
    if not common > max(float(params.open_one_sided), 3.0 / np.sqrt(len(judged))):
        return None
    spacing = median_spacing(cloud, tree)
    mirrored = [2.0 * axis[i] - cloud[rows] for i, rows in enumerate(near) if rows]
    dome = np.vstack(mirrored) if mirrored else np.empty((0, 3))
    dome = dome[tree.query(dome, k=1, workers=-1)[0] > spacing]
    if len(dome) and spacing > 0:  # one point per cell of a spacing
        _, keep = np.unique(np.floor(dome / spacing).astype(np.int64), axis=0, return_index=True)
        dome = dome[np.sort(keep)]
    if len(dome) < int(params.open_min_fill):
        return None
    rim = cloud[rows]
    centre = rim.mean(axis=0)
    normal = -u.mean(axis=0) / np.linalg.norm(u.mean(axis=0))  # away from the cloud: where the sensor was not
    dist = np.linalg.norm(rim - centre, axis=1)
    plane_normal = np.linalg.svd(rim - centre, full_matrices=False)[2][2]
    flatness = float(np.sqrt(np.mean(((rim - centre) @ plane_normal) ** 2)) / max(float(dist.mean()), 1e-300))
    opening = Opening(rows=rows, centre=centre, normal=normal, radius=float(dist.mean()), extent=2.0 * float(dist.max()),
                      flatness=flatness, roundness=float(dist.std() / max(dist.mean(), 1e-300)), surrounds=False,
                      kind="side", fill=dome, dome=dome, spacing=spacing, rim_spacing=spacing)
    opening.notes["one_sided"] = float(common)
    return opening
