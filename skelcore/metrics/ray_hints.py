"""The far-ray hints a lone query's rays leave (the leaf and the point each ray of the raster hit), kept
per query so that a later call on queries nearby starts from them (docs/boundedness.md 3.18).

An edit's update scores its moved curve samples with the exact plan, in curve order, each sample's rays
first trying the hits of the sample cast before it, 2-4 h away on a 100k tube; the samples of the curve
it was edited from lie nearer (a pruned Y's: 0.3-1.6 h). Their tables, kept by the evaluation, seed
each moved sample whose nearest old sample is nearer than the sample cast before it. Hints only order
the kernel's search (every hit is an exact ball test, every miss an exhaustive walk), so beta is the
same bit for bit with or without them.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["HintTables", "TABLES_MOST_BYTES", "seeds_for", "merged_tables"]

#: the most bytes of tables one call keeps (2 int32 per raster cell: 36,864 bytes a query at 48 rows):
#: a curve of up to about 900 samples; above it none are kept and an update casts without seeds
TABLES_MOST_BYTES = 32 * 1024 * 1024


@dataclass(frozen=True)
class HintTables:
    """Lone queries' hint tables against one cloud's kernel tree: ``cloud`` (the array given to
    ``boundedness_rays``: its tree is built the same for the same points, so the indices hold while it
    is the same array; a stale index only misorders the search, the kernel drops one out of range),
    ``origins`` (S, 3) the queries in the raster frame, ``tables`` (S, 2 x rows x bins) int32 (leaf,
    point per raster cell, -1 none), made from ``parts`` (arrays and the rows taken of each, None: all)
    when first read: an edited curve's tables are joined only when an edit after it reads them, not in
    the update that made them (7.7 MB for the Y's 200 samples, 1.7 ms)."""

    cloud: object
    origins: np.ndarray
    parts: tuple
    _joined: list = field(default_factory=list, compare=False, repr=False)
    _search: list = field(default_factory=list, compare=False, repr=False)

    def __post_init__(self) -> None:
        if not isinstance(self.parts, tuple) or not all(isinstance(p, tuple) and len(p) == 2 for p in self.parts):
            raise TypeError("HintTables.parts: a tuple of (array, rows or None) pairs (HintTables.of for one array)")

    @classmethod
    def of(cls, cloud: object, origins: np.ndarray, tables: np.ndarray) -> "HintTables":
        return cls(cloud, origins, ((tables, None),))

    @property
    def tables(self) -> np.ndarray:
        if not self._joined:
            arrays = [a if rows is None else a[rows] for a, rows in self.parts]
            self._joined.append(arrays[0] if len(arrays) == 1 else np.ascontiguousarray(np.vstack(arrays)))
        return self._joined[0]

    def __len__(self) -> int:
        return int(len(self.origins))

    def nearest(self, points: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Each point's distance to its nearest origin and that origin's row (a tree of the origins made
        at the first ask: an update asks it once per call of the kernel)."""
        if not self._search:
            self._search.append(cKDTree(self.origins))
        return self._search[0].query(points)


def seeds_for(kept: HintTables | None, centres: np.ndarray, firsts: list[int],
              nearest: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray | None:
    """Per cluster centre (in the order cast; ``firsts``: the clusters that start a stream, cast with no
    cluster before them), the row of ``kept`` to start its rays from, or -1: the nearest kept origin
    where it lies nearer than the centre cast before (whose hits the rays would start from otherwise;
    the kernel drops any start more than two reaches away). None when nothing is kept. ``nearest``:
    ``kept.nearest(centres)`` when the caller asked it already (for more points at once)."""
    if kept is None or not len(kept) or not len(centres):
        return None
    d, row = kept.nearest(centres) if nearest is None else nearest
    before = np.full(len(centres), np.inf)
    before[1:] = np.linalg.norm(np.diff(centres, axis=0), axis=1)
    before[np.asarray(firsts, np.int64)] = np.inf
    return np.where(d < before, row, -1).astype(np.int32)


def merged_tables(old: HintTables | None, made: list[HintTables], kept_at: np.ndarray | None) -> HintTables | None:
    """One :class:`HintTables` of an edited curve's samples: the rows of ``old`` at the samples kept in
    place (``kept_at``, raster frame; an origin within 1e-9 of one, since only the search's order
    hangs on it) and the tables ``made`` for the moved ones, all of one cloud (others are dropped);
    joined when first read."""
    cloud = made[0].cloud if made else (old.cloud if old is not None else None)
    parts = [m for m in made if m.cloud is cloud]
    if old is not None and old.cloud is cloud and len(old) and kept_at is not None and len(kept_at):
        d, row = old.nearest(np.asarray(kept_at, np.float64).reshape(-1, 3))
        row = np.unique(row[d <= 1e-9])
        if len(row):
            if len(old.parts) == 1:  # rows of its one array
                a, rows = old.parts[0]
                taken = ((a, row if rows is None else rows[row]),)
            else:
                taken = ((old.tables, row),)
            parts.insert(0, HintTables(cloud, old.origins[row], taken))
    if not parts:
        return None
    if len(parts) == 1:
        return parts[0]
    return HintTables(cloud, np.ascontiguousarray(np.vstack([p.origins for p in parts])),
                      tuple(part for p in parts for part in p.parts))
