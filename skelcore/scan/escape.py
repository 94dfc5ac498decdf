"""Which skeleton elements lose their boundedness through the cloud's openings (docs/metrics.md 6.1).

An element is unbounded "only because of the openings" when beta(q) <= beta* on the cloud and
beta(q) > beta* once every opening is closed by its dome (:mod:`.openings`): its rays left through
them.  Only unbounded elements are scored again, on the cloud with the domes, by the same estimator.
"""

from __future__ import annotations

import numpy as np
from scipy.spatial import cKDTree

from ..geometry import Checkpoint, no_checkpoint
from ..metrics.boundedness import boundedness
from ..params import Params
from .one_sided import one_sided_thin
from .openings import Opening, find_openings

__all__ = ["set_local_radii", "escaping_share", "fill_near_skeleton", "skeleton_openings"]


def set_local_radii(openings: list[Opening], cloud: np.ndarray, skeleton: np.ndarray) -> None:
    """Each opening's local radius: the median distance from its rim to the nearest skeleton element
    (points in the cloud's units); left NaN without skeleton elements."""
    if len(skeleton) == 0:
        return
    tree = cKDTree(skeleton)
    for o in openings:
        d, _ = tree.query(cloud[o.rows], k=1, workers=-1)
        o.local_radius = float(np.median(d))


def fill_near_skeleton(opening: Opening, skeleton: np.ndarray, radius: np.ndarray, reach: float,
                       tree: cKDTree | None = None) -> float:
    """Share of the opening's fill within ``reach`` x the local radius (``radius``: each skeleton
    element's distance to the cloud) of the nearest skeleton element.  A missing piece of a part's
    surface spans the part's cross-section, about one radius from its axis; a "fill" across the gap
    between two branches lies outside both (docs/metrics.md 6.1)."""
    if len(opening.fill) == 0 or len(skeleton) == 0:
        return 0.0
    tree = cKDTree(skeleton) if tree is None else tree
    d, i = tree.query(opening.fill, k=1, workers=-1)
    return float(np.mean(d <= reach * radius[i]))


def escaping_share(
    cloud_n: np.ndarray,
    domes_n: np.ndarray,
    elements_n: np.ndarray,
    beta: np.ndarray,
    params: Params = Params(),
    *,
    checkpoint: Checkpoint = no_checkpoint,
) -> float:
    """Share of the elements with beta <= beta* that are bounded once the domes close the openings
    (normalized coordinates; ``beta`` their boundedness on ``cloud_n``)."""
    beta = np.asarray(beta, dtype=float)
    if len(beta) == 0 or len(domes_n) == 0:
        return 0.0
    low = np.flatnonzero(~(beta > params.beta_star))
    if len(low) == 0:
        return 0.0
    closed = np.vstack([cloud_n, domes_n])
    again = boundedness(closed, elements_n[low], params=params, checkpoint=checkpoint)
    return float(np.count_nonzero(again > params.beta_star)) / len(beta)


def skeleton_openings(
    cloud: np.ndarray, skeleton: np.ndarray, params: Params = Params(), *,
    checkpoint: Checkpoint = no_checkpoint, memo: dict | None = None,
) -> tuple[list[Opening], list[Opening], np.ndarray]:
    """(every opening, those that count, the thin parts' boundary rows) of ``cloud`` judged with a
    skeleton's elements (both in the cloud's units; docs/metrics.md 6.1): boundary points of parts fewer
    than ``open_resolved_diameter`` spacings across join no opening, and a missing side counts when at
    least half its fill lies within ``open_fill_reach`` local radii of the skeleton.  Thin parts seen
    from one side add one opening, their mirrored missing side (:mod:`.one_sided`). ``memo``: see
    :func:`.openings.find_openings`."""
    skeleton = np.asarray(skeleton, dtype=float)
    tree = cKDTree(skeleton)
    thin_rows: list[int] = []
    openings = find_openings(cloud, params, checkpoint=checkpoint, thin_rows=thin_rows, memo=memo,
                             diameter=lambda pts: 2.0 * tree.query(pts, k=1, workers=-1)[0])
    thin = np.asarray(thin_rows, np.int64)
    kept: list[cKDTree] = []

    def cloud_tree() -> cKDTree:  # built once, and only when asked
        if not kept:
            kept.append(cKDTree(cloud))
        return kept[0]

    mirror = one_sided_thin(cloud, skeleton, thin, params, cloud_tree=cloud_tree, skel_tree=tree)  # seen from one side
    if mirror is not None:
        openings.append(mirror)
    counted = [o for o in openings if len(o.dome)]
    if counted:
        radius = cloud_tree().query(skeleton, k=1, workers=-1)[0]
        for o in counted:
            o.notes["fill_near_skeleton"] = fill_near_skeleton(o, skeleton, radius, params.open_fill_reach, tree)
        counted = [o for o in counted if o.kind == "end" or o.notes["fill_near_skeleton"] >= 0.5]
    return openings, counted, thin
