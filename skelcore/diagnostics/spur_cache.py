"""The spur test's nearest-ball search (whether another branch explains a cloud point,
:func:`skelcore.diagnostics.spurs.find_spurious_branches`) kept from one curve to the next of the same
cloud and params, so that an edit's update asks again only the points the edit can change
(docs/performance.md 6.10).

A point q's answer is "some curve point x of another branch than q's own has |q - x| <= reach(x)",
and reach(x) depends on x's position alone (the cloud is the same). So q keeps its earlier answer
when it was asked before, no curve position added or removed has q in its ball, and every position
whose ball holds q has a label of another branch than q's own now exactly when it had one then
(branch numbers change from curve to curve: only these relations are compared). Every other point is
asked again; the answers equal a search of the whole curve."""

from __future__ import annotations

import threading
from dataclasses import dataclass
from typing import Callable

import numpy as np
from scipy.spatial import cKDTree

__all__ = ["SpurSearch", "SpurMemo", "NearestByBalls", "same_tree", "row_hash", "row_words", "find_rows"]

#: a search function (curve points, their branches, reaches, queries, the queries' own branches) -> bool
Search = Callable[[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray], np.ndarray]
_PAIRS_MAX = 32  # (then, now) own-branch pairs tested one by one; beyond, their queries are asked again
_SIDES_MAX = 8192  # one-sidedness' kept directions (at most 400 per curve, about 150 bytes each)
_FEW = 16  # centres met one by one (a KD-tree's build and walk cost more)
_MARGIN = 1e-6  # relative: a ball counts as holding q up to this much beyond its reach (more asked again)
_KEPT_SETS = 6  # one-nearest answers of the last query sets kept (an update asks most of the last curve's points)


class NearestByBalls:
    """A KD-tree of the cloud (or of its subsample) whose one-nearest queries (rows of points) a ball
    tree of the same points answers (:meth:`skelcore.metrics.ball_tree.BallTree.nearest`: the same
    distance bits, sqrt(dx^2 + dy^2 + dz^2) of each pair, about 3 x faster from a tube's axis, where a
    KD-tree visits the whole wall); the index is that of a nearest point, on a tie perhaps another than
    the KD-tree's. Everything else is the KD-tree's (``kd``). ``balls()`` gives the ball tree (built on
    ``kd.data``, its ``perm`` to the rows). An edit's update hands it to the curve's diagnostics, which
    read the distances alone.

    The answers of the last ``_KEPT_SETS`` query sets are kept: a row with the bits of a row asked
    before (found by a hash of its bytes, its bits compared) takes that row's answer, the ball tree's
    for the same row, so the same bits; the updates of one evaluation (a repair's candidates) ask
    their curves' branch radii and outside walks mostly at the points the last one asked."""

    def __init__(self, kd: cKDTree, balls: Callable[[], object]) -> None:
        self.kd, self._balls = kd, balls
        self._kept: list[tuple[np.ndarray, ...]] = []
        self._kept_lock = threading.Lock()

    def query(self, x: np.ndarray, k: int = 1, **options: object) -> tuple[np.ndarray, np.ndarray]:
        q = np.asarray(x, dtype=float)
        if k != 1 or options or q.ndim != 2 or q.shape[1] != 3 or not len(q):
            return self.kd.query(x, k=k, **options)
        key, words = row_hash(q), row_words(q)
        d, at = np.zeros(len(q)), np.full(len(q), -1, np.int64)
        with self._kept_lock:
            kept = list(self._kept)
        for sorted_key, order, kept_words, kept_d, kept_at in reversed(kept):  # the newest first
            rows = np.flatnonzero(at < 0)
            if not len(rows):
                break
            cand, same = find_rows(sorted_key, order, kept_words, key[rows], words[rows])
            d[rows[same]], at[rows[same]] = kept_d[cand[same]], kept_at[cand[same]]
        todo = np.flatnonzero(at < 0)
        if len(todo):
            balls = self._balls()
            dd, ii = balls.nearest(q[todo], return_index=True)
            d[todo], at[todo] = dd, balls.perm[ii]
        order = np.argsort(key, kind="stable")
        with self._kept_lock:
            self._kept = (self._kept + [(key[order], order, words.copy(), d.copy(), at.copy())])[-_KEPT_SETS:]
        return d, at

    def __getattr__(self, name: str) -> object:
        if name.startswith("__") or name in ("kd", "_balls", "_kept", "_kept_lock"):  # not set yet (a copy)
            raise AttributeError(name)
        return getattr(self.kd, name)


def same_tree(a: object, b: object) -> bool:
    """Whether two trees are one (a :class:`NearestByBalls` is its KD-tree)."""
    return getattr(a, "kd", a) is getattr(b, "kd", b)


@dataclass(frozen=True)
class SpurSearch:
    """One curve's search: its points, their branch labels and reaches; the rows of the cloud's
    subsample asked (sorted), each one's own branch and answer; the subsample's size; the distinct
    positions of the points with their cloud distance, and each subsample row's nearest position and
    its distance (the own branch's search); the cloud tree the distances came from; whether another
    position lies as near to the row up to rounding (a tie the whole curve's search may break either
    way: such a row is asked again at every update)."""

    pts: np.ndarray
    labels: np.ndarray
    reach: np.ndarray
    rows: np.ndarray
    own: np.ndarray
    answer: np.ndarray
    n_use: int
    pos: np.ndarray
    pos_radius: np.ndarray
    near_pos: np.ndarray
    near_d: np.ndarray
    tree: object
    near_tied: np.ndarray | None = None
    first: np.ndarray | None = None  # each of ``pos``'s first row in ``pts`` (:func:`_distinct`), and
    inverse: np.ndarray | None = None  # each row's position: the next update's _touched sorts them not again


class SpurMemo:
    """An evaluation's spur search (``current``) and the one of the curve it was updated from
    (``previous``, None after a fresh evaluation); ``asked``: how many points the last search asked
    (of how many). Its methods are called in the order of :func:`find_spurious_branches`: ``radii``,
    ``subsample``, ``own_branch``, ``search``, all for the same curve points."""

    def __init__(self, previous: SpurSearch | None = None, shared: dict | None = None) -> None:
        self.previous = previous
        self.current: SpurSearch | None = None
        self.asked: tuple[int, int] = (0, 0)
        self.shared = {} if shared is None else shared  # the cloud's subsample, kept along the updates
        self._local = threading.local()  # one search's steps, per thread (two may finish one update at once)

    def latest(self) -> SpurSearch | None:
        """The newest search known here (what an update of this evaluation starts from)."""
        return self.current if self.current is not None else self.previous

    def next(self) -> "SpurMemo":
        """The memo of an evaluation updated from this one."""
        return SpurMemo(self.latest(), self.shared)

    def radii(self, pts: np.ndarray, tree: cKDTree) -> np.ndarray:
        """``tree.query(pts)``'s distances, kept for the positions the previous search had."""
        pos, first, inverse = _distinct(pts)
        prev = self.previous
        match = _match(prev.pos, pos) if prev is not None else np.full(len(pos), -1)
        r = np.empty(len(pos))
        known = match >= 0
        if prev is not None and same_tree(prev.tree, tree):
            r[known] = prev.pos_radius[match[known]]
        else:
            known[:] = False
        if (~known).any():
            r[~known] = tree.query(pos[~known])[0]
        self._local.now = {"pts": pts, "pos": pos, "first": first, "inverse": inverse, "match": match, "radius": r,
                           "tree": tree}
        return r[inverse]

    def sides(self, tree: cKDTree) -> dict:
        """The one-sidedness' mean directions by (position, radius) against ``tree``
        (:func:`.spur_sides.one_sidedness`'s ``kept``), shared along the updates; a new one for
        another tree, emptied beyond ``_SIDES_MAX`` entries."""
        kept = self.shared.get("sides")
        if kept is None or not same_tree(kept[0], tree) or len(kept[1]) > _SIDES_MAX:
            kept = self.shared["sides"] = (tree, {})
        return kept[1]

    def subsample(self, cloud: np.ndarray, key: tuple, make: Callable[[], np.ndarray]) -> np.ndarray:
        """``make()`` (the cloud's subsample of size and seed ``key``), made once for the same cloud array."""
        kept = self.shared.get("use")
        if kept is None or kept[0] is not cloud or kept[1] != key:
            kept = self.shared["use"] = (cloud, key, make())
        return kept[2]

    def index(self, queries: np.ndarray) -> tuple | None:
        """The subsample's first coordinates sorted and their rows, made once along the updates
        (:func:`_in_box`); None for other queries than the subsample."""
        kept = self.shared.get("use")
        if kept is None or queries is not kept[2] or queries.ndim != 2 or not len(queries):
            return None
        index = self.shared.get("index")
        if index is None or index[0] is not queries:
            order = np.argsort(queries[:, 0], kind="stable")
            index = self.shared["index"] = (queries, queries[order, 0], order)
        return index[1:]

    def own_branch(self, pts: np.ndarray, labels: np.ndarray, use: np.ndarray) -> np.ndarray:
        """The label of the curve point nearest to each row of ``use`` (``labels[cKDTree(pts).query(use)[1]]``):
        a row keeps its nearest position when that position is kept with one label, no other position
        was as near (a tie) and no added position comes as near; the others are asked of the whole curve."""
        now, prev = self._local.now, self.previous
        pos, inverse, match = now["pos"], now["inverse"], now["match"]
        lo, hi = _label_range(labels, inverse, len(pos))
        redo = np.ones(len(use), bool)
        near_pos = np.zeros(len(use), np.int64)
        near_d = np.zeros(len(use))
        tied = np.zeros(len(use), bool)
        if prev is not None and prev.n_use == len(use):
            back = np.full(len(prev.pos), -1)
            back[match[match >= 0]] = np.flatnonzero(match >= 0)
            m = back[prev.near_pos]
            ok = np.append(lo == hi, False)[m]  # kept with one label (m = -1: the appended False)
            if prev.near_tied is not None:
                ok &= ~prev.near_tied
            added = np.flatnonzero(match < 0)
            if len(added) and ok.any():
                d_new = _nearest_within(pos[added], use, np.where(ok, prev.near_d, -1.0), self.index(use))
                ok &= ~(d_new <= prev.near_d * (1 + 1e-9))
            near_pos, near_d = np.where(ok, m, 0), np.where(ok, prev.near_d, 0.0)
            redo = ~ok
        own = (lo[near_pos] if len(pos) else near_pos).astype(labels.dtype, copy=False)  # redo rows: below
        rows = np.flatnonzero(redo)
        if len(rows) and len(pos) > 1:
            # the two nearest positions: a row whose nearest is no tie (a second position as near: the
            # kd-tree's choice between them is not kept) and carries one label takes it; the others
            # ask the curve points, as the whole curve's search does
            dd, ii = cKDTree(pos).query(use[rows], k=2)
            tied[rows] = dd[:, 1] <= dd[:, 0] * (1 + 1e-9)
            plain = ~tied[rows] & (lo[ii[:, 0]] == hi[ii[:, 0]])
            one = rows[plain]
            own[one], near_pos[one], near_d[one] = lo[ii[plain, 0]], ii[plain, 0], dd[plain, 0]
            rows = rows[~plain]
        if len(rows):
            d, i = cKDTree(pts).query(use[rows])
            own[rows], near_pos[rows], near_d[rows] = labels[i], inverse[i], d
        now.update(near_pos=near_pos, near_d=near_d, near_tied=tied, n_use=len(use))
        return own

    def search(self, fn: Search, pts: np.ndarray, labels: np.ndarray, reach: np.ndarray, queries: np.ndarray,
               rows: np.ndarray, own: np.ndarray, n_use: int) -> np.ndarray:
        """``fn``'s answers for ``queries`` (rows ``rows`` of a subsample of ``n_use`` points), from
        the previous search where they cannot have changed; keeps this search as ``current``."""
        prev = self.previous
        redo = np.ones(len(rows), bool)
        answer = np.zeros(len(rows), bool)
        if prev is not None and prev.n_use == n_use and len(rows):
            if np.array_equal(prev.rows, rows):  # the same rows asked (no branch became or ceased terminal)
                at, known = np.arange(len(rows)), np.ones(len(rows), bool)
            else:
                slot = np.full(n_use, -1, np.int64)  # each subsample row's place among the rows asked before
                slot[prev.rows] = np.arange(len(prev.rows))
                at = slot[rows]
                known = at >= 0
                at = np.maximum(at, 0)
            redo = ~known
            if known.any():
                now = getattr(self._local, "now", {})
                redo |= _touched(prev, pts, labels, reach, queries, own, at, known,
                                 now if now.get("pts") is pts else None, self.index(queries))
                keep = ~redo
                answer[keep] = prev.answer[at[keep]]
        if redo.any():
            answer[redo] = fn(pts, labels, reach, queries[redo], own[redo])
        self.asked = (int(redo.sum()), len(rows))
        now = getattr(self._local, "now", {})
        if now.get("pts") is pts and now.get("n_use") == n_use:
            self.current = SpurSearch(pts, labels, reach, rows, own, answer, int(n_use), now["pos"], now["radius"],
                                      now["near_pos"], now["near_d"], now["tree"], now["near_tied"], now["first"],
                                      now["inverse"])
        return answer


def _touched(prev: SpurSearch, pts: np.ndarray, labels: np.ndarray, reach: np.ndarray, queries: np.ndarray,
             own: np.ndarray, at: np.ndarray, known: np.ndarray, now: dict | None = None,
             index: tuple | None = None) -> np.ndarray:
    """The queries asked before whose answer the edit may change. A position "explains q" when its
    ball holds q and it has a label other than q's own branch (a0 then, b0 now); a query may change
    only inside the ball of a position removed that had another label than a0, added that has another
    than b0, or kept whose "another label" differs between the two (split or merged branches): one
    search per (a0, b0) pair. Beyond ``_PAIRS_MAX`` pairs, the queries where a0 = b0 are searched in
    every position removed, added or relabelled at once and the others are all asked again. ``now``:
    the distinct positions of ``pts`` and their match with ``prev``'s, as :meth:`SpurMemo.radii` found them;
    ``index``: the queries' :meth:`SpurMemo.index`."""
    if prev.first is not None and prev.inverse is not None:  # _positions of prev, from its own search
        o_pos, o_reach = prev.pos, np.asarray(prev.reach, dtype=float)[prev.first]
        o_lo, o_hi = _label_range(prev.labels, prev.inverse, len(o_pos))
    else:
        o_pos, o_lo, o_hi, o_reach = _positions(prev.pts, prev.labels, prev.reach)
    if now is None:
        n_pos, n_lo, n_hi, n_reach = _positions(pts, labels, reach)
        match = _match(o_pos, n_pos)
    else:
        n_pos, match = now["pos"], now["match"]
        n_lo, n_hi = _label_range(labels, now["inverse"], len(n_pos))
        n_reach = np.asarray(reach, dtype=float)[now["first"]]
    common = match >= 0
    gone = np.ones(len(o_pos), bool)
    gone[match[common]] = False
    out = np.zeros(len(known), bool)
    check = np.flatnonzero(known)
    if not len(check):
        return out
    every = len(check) == len(known)  # then check is every query: no gathers through it
    to_new = _renumbering(o_lo, o_hi, n_lo, n_hi, match)  # a prune renumbers the branches after it
    o_lo, o_hi = np.minimum(to_new[o_lo + 1], to_new[o_hi + 1]), np.maximum(to_new[o_lo + 1], to_new[o_hi + 1])
    same_rows = every and len(at) == len(prev.own) and np.array_equal(at, np.arange(len(at)))
    a0 = to_new[(prev.own if same_rows else prev.own[at[check]]) + 1]
    b0 = own if every else own[check]
    a_lo, a_hi = o_lo[match[common]], o_hi[match[common]]  # kept positions, then and now
    b_lo, b_hi = n_lo[common], n_hi[common]
    base = int(max(a0.max(), b0.max(), 0)) + 2  # labels are >= -1: one integer per (a0, b0) pair
    pairs, which = _pairs((a0 + 1) * base + (b0 + 1), base)
    # per pair when few (a removed or moved position of q's own branch cannot have explained q);
    # else one search of every position removed, added or relabelled for the queries where a0 = b0
    if len(pairs) > _PAIRS_MAX:
        same = a0 == b0
        relabelled = (a_lo != b_lo) | (a_hi != b_hi)
        balls = np.vstack([o_pos[gone], n_pos[~common], n_pos[common][relabelled]])
        radii = np.concatenate([o_reach[gone], n_reach[~common], n_reach[common][relabelled]])
        if len(balls) and same.any():
            out[check[same]] = _inside_any(balls, radii, queries[check[same]])
        check, a0, b0 = check[~same], a0[~same], b0[~same]
        if not len(check):
            return out
        pairs, which = _pairs((a0 + 1) * base + (b0 + 1), base)
        if len(pairs) > _PAIRS_MAX:
            out[check] = True
            return out
    per_pair = []
    for key in pairs.tolist():
        x, y = key // base - 1, key % base - 1
        removed = gone & ~((o_lo == x) & (o_hi == x))
        added = ~common & ~((n_lo == y) & (n_hi == y))
        differs = ~((a_lo == x) & (a_hi == x)) != ~((b_lo == y) & (b_hi == y))
        balls = np.vstack([o_pos[removed], n_pos[~common][added[~common]], n_pos[common][differs]])
        radii = np.concatenate([o_reach[removed], n_reach[~common][added[~common]], n_reach[common][differs]])
        per_pair.append((balls, radii))
    if index is None:  # each pair's queries, then those in its balls' box (_inside_any)
        for j, (balls, radii) in enumerate(per_pair):
            if len(balls):
                sel = check[which == j]
                out[sel] = _inside_any(balls, radii, queries[sel])
        return out
    # the queries in the box of every pair's balls (two bisections of the index), then each pair's among them
    lo, hi = _balls_box([b for b, _ in per_pair], [r for _, r in per_pair])
    if lo is None:
        return out
    near = _in_box(queries, lo, hi, index)
    pair_of = np.full(len(known), -1, np.int64)
    pair_of[check] = which
    near_pair = pair_of[near]
    for j, (balls, radii) in enumerate(per_pair):
        if len(balls):
            sel = near[near_pair == j]
            out[sel] = _inside_any(balls, radii, queries[sel])
    return out


def _balls_box(centres: list[np.ndarray], radii: list[np.ndarray]) -> tuple[np.ndarray | None, np.ndarray | None]:
    """The box of the balls (centre, radius) with a finite radius >= 0 in all the lists, widened as
    :func:`_inside_any` widens its own; (None, None) without one."""
    c = np.vstack([np.zeros((0, 3))] + [np.asarray(x, float).reshape(-1, 3) for x in centres])
    r = np.concatenate([np.zeros(0)] + [np.asarray(x, float) for x in radii])
    ok = np.isfinite(r) & (r >= 0)
    if not ok.any():
        return None, None
    big = float(r[ok].max()) * (1 + _MARGIN)
    return c[ok].min(axis=0) - big, c[ok].max(axis=0) + big


def _renumbering(o_lo: np.ndarray, o_hi: np.ndarray, n_lo: np.ndarray, n_hi: np.ndarray, match: np.ndarray
                 ) -> np.ndarray:
    """One-to-one old label -> new label (at old label + 1): each old branch to the new label most of
    its kept one-label positions carry, when no old branch with more took it; the rest to labels no new
    position has. "Another branch than q's own" reads the same under any one-to-one renaming, so the
    answers kept stay exact; the renaming only makes the (then, now) pairs few again after an edit
    renumbered the branches (one pair per query otherwise, and every query asked again)."""
    n_old = int(o_hi.max()) + 2 if len(o_hi) else 1
    top = int(n_hi.max()) + 1 if len(n_hi) else 0
    kept = np.flatnonzero(match >= 0)
    was = match[kept]
    one = (o_lo[was] == o_hi[was]) & (n_lo[kept] == n_hi[kept])
    key = (o_lo[was][one] + 1) * (top + 1) + (n_lo[kept][one] + 1)
    pairs, counts = np.unique(key, return_counts=True)
    to_new = np.full(n_old, np.iinfo(np.int64).min, np.int64)
    taken: set[int] = set()
    for k in pairs[np.lexsort((pairs, -counts))].tolist():  # the most shared first, ties by label
        x, y = k // (top + 1), k % (top + 1) - 1
        if to_new[x] == np.iinfo(np.int64).min and y not in taken:
            to_new[x] = y
            taken.add(y)
    free = to_new == np.iinfo(np.int64).min
    to_new[free] = top + np.arange(int(free.sum()))
    return to_new


def _pairs(key: np.ndarray, base: int) -> tuple[np.ndarray, np.ndarray]:
    """``np.unique(key, return_inverse=True)`` of non-negative integers below ``base`` squared, by
    counting when that range is small (the queries' (then, now) own-branch pairs; no sort of 100k)."""
    if base * base > 4 * len(key) + 1024:
        pairs, which = np.unique(key, return_inverse=True)
        return pairs, np.ravel(which)
    present = np.bincount(key, minlength=base * base) > 0
    pairs = np.flatnonzero(present)
    rank = np.cumsum(present) - 1
    return pairs, rank[key]


def _distinct(pts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The distinct rows of ``pts`` (in byte order), the first row of each and each row's one."""
    pts = np.ascontiguousarray(pts, dtype=float)
    if not len(pts):
        return pts.reshape(0, 3), np.zeros(0, np.int64), np.zeros(0, np.int64)
    _, first, inverse = np.unique(_void(pts), return_index=True, return_inverse=True)
    return pts[first], first, np.ravel(inverse)


def _label_range(labels: np.ndarray, inverse: np.ndarray, n: int) -> tuple[np.ndarray, np.ndarray]:
    """The lowest and highest label at each of ``n`` positions."""
    lo = np.full(n, np.iinfo(np.int64).max)
    hi = np.full(n, np.iinfo(np.int64).min)
    np.minimum.at(lo, inverse, labels)
    np.maximum.at(hi, inverse, labels)
    return lo, hi


def _match(old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """For each row of ``new``, the row of ``old`` (distinct rows) with the same bits, or -1: the rows
    looked up by a 64-bit hash of their bytes among ``old``'s sorted hashes, each found one's bits compared
    (about 8 x less CPU than a sort of both rows' bytes at 50k rows); when two rows of ``old`` share a
    hash, by that sort (:func:`_match_sorted`)."""
    if not len(old) or not len(new):
        return np.full(len(new), -1, np.int64)
    old_key, new_key = row_hash(old), row_hash(new)
    order = np.argsort(old_key)
    sorted_key = old_key[order]
    if len(sorted_key) > 1 and not np.all(sorted_key[1:] != sorted_key[:-1]):
        return _match_sorted(old, new)
    cand, same = find_rows(sorted_key, order, row_words(old), new_key, row_words(new))
    return np.where(same, cand, -1).astype(np.int64)


def find_rows(sorted_key: np.ndarray, order: np.ndarray, kept_words: np.ndarray, key: np.ndarray,
              words: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Each asked row's candidate among kept rows (``order`` sorts their :func:`row_hash` into
    ``sorted_key``; ``kept_words`` their :func:`row_words`) and whether it has the same bits: the row
    of equal hash, its words compared."""
    slot = np.minimum(np.searchsorted(sorted_key, key), len(order) - 1)
    cand = order[slot]
    return cand, (sorted_key[slot] == key) & np.all(kept_words[cand] == words, axis=1)


def row_words(pts: np.ndarray) -> np.ndarray:
    """The rows' bytes as 64-bit words (the same bits, -0.0 and 0.0 apart)."""
    rows = np.ascontiguousarray(pts, dtype=float)
    return rows.view(np.uint64).reshape(len(rows), -1)


def row_hash(pts: np.ndarray) -> np.ndarray:
    """A 64-bit hash of each row's bytes (equal bits, equal hashes; multiplications wrap around)."""
    w = row_words(pts)
    mix = np.array([0x9E3779B97F4A7C15, 0xC2B2AE3D27D4EB4F, 0x165667B19E3779F9, 0xD6E8FEB86659FD93], np.uint64)
    h = np.zeros(len(w), np.uint64)
    for k in range(w.shape[1]):
        h = (h ^ (w[:, k] * mix[k % len(mix)])) * mix[(k + 1) % len(mix)]
        h ^= h >> np.uint64(29)
    return h


def _match_sorted(old: np.ndarray, new: np.ndarray) -> np.ndarray:
    """:func:`_match` by one sort of both rows' bytes."""
    _, key = np.unique(np.concatenate([_void(old), _void(new)]), return_inverse=True)
    key = np.ravel(key)
    at = np.full(int(key.max()) + 1, -1, np.int64)
    at[key[:len(old)]] = np.arange(len(old))
    return at[key[len(old):]]


def _nearest_within(centres: np.ndarray, queries: np.ndarray, bound: np.ndarray, index: tuple | None = None
                    ) -> np.ndarray:
    """Each query's distance to the nearest centre, inf where none is within ``bound`` (per query; a
    negative bound skips the query) up to a small margin; perhaps a last bit off the KD-tree's (it only
    chooses the rows asked again, which get the whole search's answer). ``index``: as :func:`_in_box`'s."""
    out = np.full(len(queries), np.inf)
    if not len(queries) or not bound.max() >= 0:
        return out
    lo, hi = centres.min(axis=0), centres.max(axis=0)
    b = bound * (1 + _MARGIN)
    # within the largest bound of the centres' box (no copy of the queries), then within each one's own
    near = np.sort(_in_box(queries, lo - b.max(), hi + b.max(), index))
    near = near[bound[near] >= 0]
    for k in range(queries.shape[1]):
        col, bk = queries[near, k], b[near]
        near = near[(col >= lo[k] - bk) & (col <= hi[k] + bk)]
    if len(near) and len(centres) <= _FEW:  # a moved vertex: a few centres, every distance at once
        q = queries[near]
        d2 = np.full(len(near), np.inf)
        for c in centres:
            np.minimum(d2, ((q - c) ** 2).sum(axis=1), out=d2)
        out[near] = np.sqrt(d2)
    elif len(near):
        out[near] = cKDTree(centres).query(queries[near], k=1)[0]
    return out


def _positions(pts: np.ndarray, labels: np.ndarray, reach: np.ndarray) -> tuple[np.ndarray, ...]:
    """The distinct positions of curve points, each one's lowest and highest label and its reach (the
    same at a position)."""
    pos, first, inverse = _distinct(pts)
    lo, hi = _label_range(labels, inverse, len(pos))
    return pos, lo, hi, np.asarray(reach, dtype=float)[first]


def _in_box(queries: np.ndarray, lo: np.ndarray, hi: np.ndarray, index: tuple | None = None) -> np.ndarray:
    """The rows of ``queries`` with lo <= q <= hi in every coordinate (``np.flatnonzero(np.all(...))``,
    perhaps in another order), one coordinate at a time on the rows left (a small box of 100k queries:
    about 7 x faster). ``index``: the queries' first coordinates sorted and their rows
    (:meth:`SpurMemo.index`), which give the rows within the first bounds by two bisections."""
    if index is not None:
        xs, order = index
        rows = order[np.searchsorted(xs, lo[0], "left"):np.searchsorted(xs, hi[0], "right")]
        for k in range(1, queries.shape[1]):
            col = queries[rows, k]
            rows = rows[(col >= lo[k]) & (col <= hi[k])]
        return rows
    rows = np.arange(len(queries))
    for k in range(queries.shape[1]):
        col = queries[rows, k] if k else queries[:, 0]
        rows = rows[(col >= lo[k]) & (col <= hi[k])]
    return rows


def _void(pts: np.ndarray) -> np.ndarray:
    return np.ascontiguousarray(pts, dtype=float).view(np.dtype((np.void, 8 * pts.shape[1])))[:, 0]


def _inside_any(centres: np.ndarray, radii: np.ndarray, queries: np.ndarray) -> np.ndarray:
    """Whether each query lies within some ball (centre, radius), up to ``_MARGIN`` beyond it (never
    less): the nearest ball in the lifted 4-D distance |q - c|^2 - r^2 + R^2 (R the largest radius)."""
    out = np.zeros(len(queries), bool)
    ok = np.isfinite(radii) & (radii >= 0)
    if not len(queries) or not ok.any():
        return out
    centres, radii = centres[ok], radii[ok]
    big = float(radii.max())
    lo, hi = centres.min(axis=0) - big * (1 + _MARGIN), centres.max(axis=0) + big * (1 + _MARGIN)
    near = _in_box(queries, lo, hi)
    if not len(near):
        return out
    lifted = np.column_stack([centres, np.sqrt(np.maximum(big * big - radii * radii, 0.0))])
    q4 = np.column_stack([queries[near], np.zeros(len(near))])
    d, _ = cKDTree(lifted).query(q4, k=1, distance_upper_bound=big * (1 + _MARGIN) + 1e-300)
    out[near] = np.isfinite(d)
    return out
