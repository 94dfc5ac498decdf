"""Samples along a curve skeleton and the curve direction at each (docs/metrics.md 3; paper, definitions
"curve skeleton point" and "associated points").

The samples feed curve boundedness (docs/metrics.md 2) and curve centeredness (docs/metrics.md 3); the directions define
the cutting slabs of curve centeredness, so only the line through a direction matters, not its sign.
The reference tool's sampling quirk, direction rules and degenerate cases are listed in
:func:`sample_curve`.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..curve import CurveSkeleton
from ..geometry import unit_rows

__all__ = ["CurveSamples", "sample_curve", "sample_counts", "SAMPLING_METHODS", "canonical_edges"]

#: ``Params.curve_sampling``: the reference tool's per-edge orientation by vertex index, or one that
#: depends only on the geometry and the graph (docs/metrics.md 3, "Vertex numbering")
SAMPLING_METHODS = ("toolbox", "invariant")


@dataclass(frozen=True)
class CurveSamples:
    """Samples of a curve skeleton (docs/metrics.md 3).

    points : (S, 3) sample positions.
    edge : (S,) int, row of ``curve.edges`` the sample lies on.
    t : (S,) float, fraction along that edge from its lower-index vertex: in (0, 1] under the
        toolbox's sampling, in [0, 1] under the invariant one (an edge walked from its higher-index end).
    directions : (S, 3) unit curve directions; NaN rows where the direction is invalid (joints,
        zero-length edges).
    """

    points: np.ndarray
    edge: np.ndarray
    t: np.ndarray
    directions: np.ndarray

    def __len__(self) -> int:
        return int(len(self.points))


def sample_counts(edge_lengths: np.ndarray, n_samples: int) -> np.ndarray:
    """n_e = max(1, round(len_e / total_len * S)) per edge, MATLAB rounding (docs/metrics.md 3).

    With a total length of 0 every edge gets one sample.
    """
    lengths = np.asarray(edge_lengths, dtype=float)
    total = float(lengths.sum())
    if not total > 0:
        return np.ones(len(lengths), dtype=np.int64)
    share = lengths / total * float(n_samples)
    # share >= 0, where MATLAB's round (geometry.matlab_round) is floor(x + 0.5)
    return np.maximum(1, np.floor(share + 0.5)).astype(np.int64)


def sample_curve(
    curve: CurveSkeleton, n_samples: int, *, collinear_cos: float = 0.99, method: str = "toolbox"
) -> CurveSamples:
    """Sample ``curve`` with about ``n_samples`` points and give the curve direction at each (docs/metrics.md 3).

    ``method`` "toolbox" (default) walks every edge from its lower-index vertex, as below, so the
    samples depend on how the vertices are numbered; "invariant" walks every branch from a canonical
    end instead (:func:`canonical_edges`; docs/metrics.md 3): the same counts per edge, the same
    directions, only which end vertex of each branch is sampled changes.

    Conventions (the reference tool's, kept on purpose):

    * Edge (i, j) with i < j gets n_e = max(1, round(len_e / total_len * S)) samples (MATLAB rounding,
      half away from zero) at fractions t = 1/n_e, ..., 1 from v_i to v_j: the start vertex is excluded
      and the end vertex included, so the lowest-index end of a path is never sampled and a closed loop
      samples one vertex twice. The total is sum(n_e), which may differ from S by rounding.
    * Direction inside an edge (t < 1): the edge direction v_j - v_i. At the end vertex (t == 1), by
      the degree of v_j: 1 -> the edge direction; 2 -> the tangent at v_j of the circle through v_i,
      v_j and v_j's other neighbour b (the chord b - v_i when |cos| of the angle at v_j is at or above
      ``collinear_cos``, i.e. nearly straight or a hairpin); >= 3 (a joint) -> NaN.
    * Sign: every direction points "forward" along the sampled edge, from v_i towards v_j (and on to b
      at a degree-2 vertex). Directions are unit vectors or NaN rows.

    Degenerate cases:

    * No edges: zero samples (empty arrays).
    * Zero-length edge: one sample at v_j (n_e = max(1, 0) = 1); its edge direction is undefined, so
      its direction is NaN unless v_j has degree 2 and the chord to the other neighbour is defined.
    * All edges of zero length (total length 0): one sample per edge, as above.
    * Degree-2 vertex coinciding with a neighbour: the circle is undefined; the chord b - v_i is used
      (NaN if that is zero too).

    Examples
    --------
    >>> c = CurveSkeleton.from_raw([[0, 0, 0], [1, 0, 0], [3, 0, 0], [4, 0, 0]], [[0, 1], [1, 2], [2, 3]])
    >>> sample_curve(c, 8).t.tolist()
    [0.5, 1.0, 0.25, 0.5, 0.75, 1.0, 0.5, 1.0]
    """
    if int(n_samples) < 1:
        raise ValueError(f"n_samples={n_samples!r}: must be a positive integer")
    if not 0.0 <= float(collinear_cos) <= 1.0:
        raise ValueError(f"collinear_cos={collinear_cos!r}: must be in [0, 1]")
    if method not in SAMPLING_METHODS:
        raise ValueError(f"method={method!r}: must be one of {', '.join(SAMPLING_METHODS)}")
    vertices = np.asarray(curve.vertices, dtype=float)
    edges = np.asarray(curve.edges, dtype=np.int64).reshape(-1, 2)
    if len(edges) == 0:
        empty = np.empty((0, 3))
        return CurveSamples(points=empty, edge=np.empty(0, np.int64), t=np.empty(0), directions=empty.copy())
    if method == "invariant":
        rows, oriented = canonical_edges(vertices, edges)
        walked = _sample_edges(vertices, oriented, int(n_samples), float(collinear_cos))
        flipped = oriented[walked.edge, 0] != edges[rows[walked.edge], 0]
        t = np.where(flipped, 1.0 - walked.t, walked.t)  # from the lower-index vertex, as documented
        return CurveSamples(points=walked.points, edge=rows[walked.edge], t=t, directions=walked.directions)
    return _sample_edges(vertices, edges, int(n_samples), float(collinear_cos))


def _sample_edges(vertices: np.ndarray, edges: np.ndarray, n_samples: int, collinear_cos: float) -> CurveSamples:
    """The toolbox's sampling of every edge (i, j) from v_i to v_j (conventions of :func:`sample_curve`)."""
    start, end = vertices[edges[:, 0]], vertices[edges[:, 1]]
    counts = sample_counts(np.linalg.norm(end - start, axis=1), int(n_samples))
    edge_of = np.repeat(np.arange(len(edges)), counts)
    # step k = 1..n_e within each edge
    offsets = np.cumsum(counts) - counts
    step = np.arange(len(edge_of)) - np.repeat(offsets, counts) + 1
    n_e = counts[edge_of]
    t = step / n_e
    at_end = step == n_e
    t[at_end] = 1.0
    points = start[edge_of] + t[:, None] * (end - start)[edge_of]
    points[at_end] = end[edge_of[at_end]]  # exactly the vertex, no rounding error

    edge_dir = unit_rows(end - start)
    directions = edge_dir[edge_of]
    end_dir = _end_vertex_directions(vertices, edges, edge_dir, float(collinear_cos))
    directions[at_end] = end_dir[edge_of[at_end]]
    return CurveSamples(points=points, edge=edge_of, t=t, directions=directions)


def _end_vertex_directions(
    vertices: np.ndarray, edges: np.ndarray, edge_dir: np.ndarray, collinear_cos: float
) -> np.ndarray:
    """Direction at the end vertex v_j of every edge (i, j), by v_j's degree (docs/metrics.md 3)."""
    n_v = len(vertices)
    degree = np.bincount(edges.ravel(), minlength=n_v)
    i, j = edges[:, 0], edges[:, 1]
    out = np.full((len(edges), 3), np.nan)

    deg_j = degree[j]
    one = deg_j == 1
    out[one] = edge_dir[one]

    two = np.flatnonzero(deg_j == 2)
    if len(two):
        # the other neighbour b of each degree-2 end vertex: sum of its two neighbours minus v_i
        neighbour_sum = np.zeros(n_v, dtype=np.int64)
        np.add.at(neighbour_sum, edges[:, 0], edges[:, 1])
        np.add.at(neighbour_sum, edges[:, 1], edges[:, 0])
        a = vertices[i[two]]
        v = vertices[j[two]]
        b = vertices[neighbour_sum[j[two]] - i[two]]
        out[two] = _circle_tangent(a, v, b, collinear_cos)
    return out


def _circle_tangent(a: np.ndarray, v: np.ndarray, b: np.ndarray, collinear_cos: float) -> np.ndarray:
    """Unit tangent at v of the circle through a, v, b, oriented from a towards b.

    With d1 = v - a and d2 = b - v the tangent is parallel to d1/|d1|^2 + d2/|d2|^2 (inscribed-angle
    theorem; no circumcentre needed). Nearly collinear points (|cos| >= collinear_cos, straight or
    hairpin) or a neighbour at v use the chord b - a instead (docs/metrics.md 3).
    """
    d1 = v - a
    d2 = b - v
    n1 = np.einsum("ij,ij->i", d1, d1)
    n2 = np.einsum("ij,ij->i", d2, d2)
    with np.errstate(invalid="ignore", divide="ignore"):
        cos = np.einsum("ij,ij->i", d1, d2) / np.sqrt(n1 * n2)
        tangent = d1 / n1[:, None] + d2 / n2[:, None]
    chord = ~(np.abs(cos) < collinear_cos)  # also where cos is NaN (a neighbour at v)
    tangent[chord] = (b - a)[chord]
    return unit_rows(tangent)


def canonical_edges(vertices: np.ndarray, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The edges oriented and ordered by the geometry and the graph alone (docs/metrics.md 3).

    The curve is cut into branches at every vertex of degree other than 2 (closed loops of degree-2
    vertices are branches too). Each branch is walked from the end whose sequence of vertex coordinates
    is lexicographically smaller (compared from that end: the end vertices' coordinates first, the next
    vertices' on a tie), so its edges point one way and every inner vertex ends exactly one edge.  A loop
    starts at its lexicographically smallest vertex, towards its smaller neighbour.  The oriented edges
    are then sorted lexicographically by (start coordinates, end coordinates).

    Returns ``rows`` (the row of ``edges`` each oriented edge came from) and ``oriented`` (E, 2).
    Relabelling the vertices or reordering and reversing the edges changes neither the oriented edges'
    coordinates nor their order (up to exactly coincident vertices).
    """
    vertices = np.asarray(vertices, dtype=float)
    edges = np.asarray(edges, dtype=np.int64).reshape(-1, 2)
    n_v, n_e = len(vertices), len(edges)
    degree = np.bincount(edges.ravel(), minlength=n_v)
    # incidence lists: for every vertex its (edge row, other end) pairs
    ends = np.concatenate([edges[:, 0], edges[:, 1]])
    others = np.concatenate([edges[:, 1], edges[:, 0]])
    rows_of = np.concatenate([np.arange(n_e), np.arange(n_e)])
    order = np.argsort(ends, kind="stable")
    start_at = np.concatenate([[0], np.cumsum(degree)])
    inc_edge, inc_other = rows_of[order].tolist(), others[order].tolist()
    start_at = start_at.tolist()
    deg = degree.tolist()
    used = np.zeros(n_e, bool)
    oriented = edges.copy()

    def walk(first: int, k: int) -> tuple[list[int], list[int]]:
        """From ``first`` along incidence ``k`` until a vertex of degree other than 2, or ``first`` again."""
        row, cur = inc_edge[k], inc_other[k]
        path, path_rows = [first, cur], [row]
        while deg[cur] == 2 and cur != first:
            a = start_at[cur]
            k = a if inc_edge[a] != row else a + 1
            row, cur = inc_edge[k], inc_other[k]
            path.append(cur)
            path_rows.append(row)
        return path, path_rows

    def smaller(one: list[int], two: list[int]) -> bool:
        """Whether path ``two``'s coordinate sequence is lexicographically smaller than ``one``'s."""
        x, y = vertices[one].ravel(), vertices[two].ravel()
        diff = np.flatnonzero(x != y)
        return bool(diff.size) and bool(y[diff[0]] < x[diff[0]])

    def keep(path: list[int], path_rows: list[int]) -> None:
        used[path_rows] = True
        oriented[path_rows] = np.column_stack([path[:-1], path[1:]])

    for v in range(n_v):
        if deg[v] == 2:
            continue
        for k in range(start_at[v], start_at[v + 1]):
            if not used[inc_edge[k]]:
                path, path_rows = walk(v, k)
                if smaller(path, path[::-1]):
                    path, path_rows = path[::-1], path_rows[::-1]
                keep(path, path_rows)
    left = np.flatnonzero(~used)
    if len(left):  # closed loops of degree-2 vertices: from the smallest vertex, to its smaller neighbour
        loop_vertices = np.unique(edges[left].ravel())
        for v in loop_vertices[np.lexsort(vertices[loop_vertices].T[::-1])].tolist():
            if used[inc_edge[start_at[v]]]:
                continue
            one, two = walk(v, start_at[v]), walk(v, start_at[v] + 1)
            keep(*(two if smaller(one[0], two[0]) else one))

    a, b = vertices[oriented[:, 0]], vertices[oriented[:, 1]]
    rows = np.lexsort((b[:, 2], b[:, 1], b[:, 0], a[:, 2], a[:, 1], a[:, 0]))
    return rows, oriented[rows]
