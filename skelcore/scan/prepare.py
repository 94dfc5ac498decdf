"""``--remove-outliers``: the cloud without its stray points, and the skeletal rows that go with them
(docs/metrics.md 6.4).

The cloud's outliers (:func:`.outliers.find_outliers`) are left out.  Pointwise correspondence (row i
of the skeletal set is where cloud row i went, so the set is as dense as the cloud) also drops the rows
whose skeletal point is far from every other (:func:`.outliers.isolated_rows`), from both; an index
correspondence drops the skeletal rows whose cloud row went and renumbers the rest; a skeletal set
without correspondence (reverse projection, none; often sparse by design) is kept whole.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..geometry import Checkpoint, kd_tree, no_checkpoint
from ..params import Params
from .outliers import Outliers, find_outliers, isolated_rows

__all__ = ["Strays", "find_strays", "without_strays"]


@dataclass(frozen=True)
class Strays:
    """The stray points of a cloud and of its skeletal set."""

    cloud: Outliers  # the cloud's outliers
    skeletal_rows: np.ndarray  # rows of skeletal points far from every other skeletal point

    def to_dict(self) -> dict:
        return dict(self.cloud.to_dict(), skeletal_rows=[int(r) for r in self.skeletal_rows])


def find_strays(cloud: np.ndarray, skeletal: np.ndarray | None, params: Params = Params(), *,
                pointwise: bool = False, checkpoint: Checkpoint = no_checkpoint) -> Strays:
    """The cloud's outliers and, for a skeletal set in pointwise correspondence, its isolated points."""
    cloud = np.asarray(cloud, dtype=float)
    tree = kd_tree(cloud, checkpoint, 0.0) if len(cloud) > 1 else None  # one tree for both tests
    found = find_outliers(cloud, params, checkpoint=checkpoint, tree=tree)
    iso = (isolated_rows(skeletal, found.spacing, params, lambda f: checkpoint(1.0), cloud=cloud, cloud_tree=tree)
           if skeletal is not None and pointwise else np.zeros(0, np.int64))
    return Strays(found, iso)


def without_strays(
    cloud: np.ndarray,
    skeletal: np.ndarray | None,
    index: np.ndarray | None,
    pointwise: bool,
    params: Params = Params(),
    *,
    checkpoint: Checkpoint = no_checkpoint,
) -> tuple[np.ndarray, np.ndarray | None, np.ndarray | None, Strays, np.ndarray, int]:
    """(cloud, skeletal, index) without the strays (module docstring), the strays found, the cloud rows
    dropped and the number of skeletal rows dropped."""
    strays = find_strays(cloud, skeletal, params, pointwise=pointwise, checkpoint=checkpoint)
    drop = np.zeros(len(cloud), bool)
    drop[strays.cloud.rows] = True
    if skeletal is None:
        return cloud[~drop], None, None, strays, np.flatnonzero(drop), 0
    skel_drop = np.zeros(len(skeletal), bool)
    skel_drop[strays.skeletal_rows] = True
    if pointwise:
        drop |= skel_drop
        skel_drop = drop
    elif index is not None:
        skel_drop |= drop[index]
    keep = ~drop
    if index is not None and not pointwise:
        index = (np.cumsum(keep) - 1)[index[~skel_drop]]
    return cloud[keep], skeletal[~skel_drop], index, strays, np.flatnonzero(drop), int(np.count_nonzero(skel_drop))
