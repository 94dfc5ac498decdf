"""Direct least-squares ellipse fit (Fitzgibbon, Pilu & Fisher 1999) in the numerically stable
form of Halir & Flusser (1998): the cross-section centre and semi-axes l_a, l_b of curve
centeredness (paper Eq. 11, ``eq.curve_point_centeredness``, and its remark; docs/metrics.md 3).  The paper
prefers a fitted ellipse to the barycentre as the centre of a partly sampled cross-section.
"""

from __future__ import annotations

from typing import Any, NamedTuple

import numpy as np

from . import _rings

__all__ = ["fit_ellipse", "fit_ellipses", "EllipseSums", "ellipse_sums", "ellipses_from_sums"]

# C1^-1 for the constraint 4ac - b^2 = 1 on (a, b, c): C1 = [[0, 0, 2], [0, -1, 0], [2, 0, 0]]
_C1_INV = np.array([[0.0, 0.0, 0.5], [0.0, -1.0, 0.0], [0.5, 0.0, 0.0]])
_DESIGN_ROWS = 1 << 15  # rows of D filled per compiled call, in one reused buffer (1.5 MB: stays in cache)


def fit_ellipse(xy: np.ndarray) -> tuple[np.ndarray, np.ndarray, float] | None:
    """Fit an ellipse to 2-D points; return ``(center, semi_axes, angle)`` or None.

    The conic a x^2 + b xy + c y^2 + d x + e y + f = 0 minimising the algebraic distance subject to
    4ac - b^2 = 1 (which forces an ellipse), solved through the reduced 3x3 eigenproblem of
    Halir & Flusser. The points are centred and scaled to unit RMS radius first: the constrained
    problem is invariant under translation and isotropic scaling, and this keeps the scatter
    matrices well conditioned.

    Parameters
    ----------
    xy : (n, 2) points.

    Returns
    -------
    center : (2,) centre of the conic.
    semi_axes : (2,) semi-axis lengths, major first.
    angle : direction of the major axis, radians in (-pi/2, pi/2].
    None when there are fewer than 5 points, the points are degenerate (e.g. collinear, all on
    two lines) or no real ellipse results.

    Examples
    --------
    >>> t = np.linspace(0, 2 * np.pi, 20, endpoint=False)
    >>> center, axes, angle = fit_ellipse(np.column_stack([3 + 2 * np.cos(t), -1 + np.sin(t)]))
    >>> np.round(center, 9).tolist(), np.round(axes, 9).tolist(), round(angle, 9)
    ([3.0, -1.0], [2.0, 1.0], 0.0)
    """
    xy = np.asarray(xy, dtype=float)
    if xy.ndim != 2 or xy.shape[1] != 2:
        raise ValueError(f"expected (n, 2) points, got shape {xy.shape}")
    centers, axes, angles = fit_ellipses(xy, np.array([0, len(xy)]))
    if np.isnan(centers[0, 0]):
        return None
    return centers[0], axes[0], float(angles[0])


def fit_ellipses(xy: np.ndarray, starts: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """:func:`fit_ellipse` of many point sets at once: set i is ``xy[starts[i]:starts[i + 1]]``.

    Each set's scatter matrices are one BLAS product (:func:`ellipse_sums`); every later step
    (condition, solve, the 3 x 3 eigenproblem, the conic's geometry) is one LAPACK call on the stacked
    matrices of all sets (:func:`ellipses_from_sums`), instead of a dozen numpy calls per set (curve
    centeredness fits thousands of cross-sections, docs/performance.md 6.5).  Set i's numbers never
    depend on the other sets, so one set alone gives the same bits as in a batch.

    Returns ``centers`` (S, 2), ``semi_axes`` (S, 2, major first) and ``angles`` (S,), NaN for a set
    that has fewer than 5 points, a non-finite point, degenerate points (e.g. collinear) or no real
    ellipse.
    """
    xy = np.asarray(xy, dtype=float).reshape(-1, 2)
    starts = np.asarray(starts, dtype=np.int64)
    return ellipses_from_sums(ellipse_sums(xy[:, 0].copy(), xy[:, 1].copy(), starts), len(starts) - 1)


class EllipseSums(NamedTuple):
    """The per-set part of :func:`fit_ellipses`: the sets fitted (``use``), their centroids
    (``origin``, (K, 2)), RMS radii (``scale``) and 6 x 6 scatter matrices of the scaled points (``sc``)."""

    use: np.ndarray
    origin: np.ndarray
    scale: np.ndarray
    sc: np.ndarray

    def shifted(self, offset: int) -> "EllipseSums":
        """The same sums with set numbers moved by ``offset`` (a batch's place among more sets)."""
        return self._replace(use=self.use + offset)

    @staticmethod
    def joined(parts: "list[EllipseSums]") -> "EllipseSums":
        """Several batches' sums as one (set numbers as they are)."""
        if not parts:
            return EllipseSums(np.zeros(0, np.int64), np.zeros((0, 2)), np.zeros(0), np.zeros((0, 6, 6)))
        return EllipseSums(*(np.concatenate(arrays) for arrays in zip(*parts)))


def ellipse_sums(x: np.ndarray, y: np.ndarray, starts: np.ndarray, scratch: Any = None) -> EllipseSums:
    """Centroid, RMS radius and scatter matrix of every set ``x[starts[i]:starts[i + 1]]`` (and y): the
    points centred and scaled to unit RMS radius (the constrained problem is invariant under both), then
    D^T D of D = [x^2, xy, y^2, x, y, 1] (one BLAS product per set: a set may hold tens of thousands of
    points).  Centroids, radii and the rows of D come from the compiled ``_rings.design`` for many sets per
    call (numpy's arithmetic: running sums, a pairwise mean; the same bits as :func:`_reference_sums`,
    tested), into one reused buffer; only the products stay per set (docs/performance.md 6.5).  ``scratch``:
    an object whose ``design`` array is that buffer, kept by the caller (grown here when too small)."""
    x, y = np.ascontiguousarray(x, dtype=float), np.ascontiguousarray(y, dtype=float)
    starts = np.ascontiguousarray(starts, dtype=np.int64)
    n_sets = len(starts) - 1
    if n_sets < 1:
        return EllipseSums.joined([])
    big = int(np.diff(starts).max())
    rows = min(int(starts[-1] - starts[0]), max(big, _DESIGN_ROWS))
    design = getattr(scratch, "design", None)
    if design is None or len(design) < rows:
        design = np.empty((max(rows, _DESIGN_ROWS if scratch is not None else 0), 6))
        if scratch is not None:
            scratch.design = design
    parts, scs = [], []
    lo = 0
    while lo < n_sets:  # sets lo .. hi - 1: at most _DESIGN_ROWS rows (or one larger set)
        hi = min(n_sets, max(lo + 1, int(np.searchsorted(starts, starts[lo] + _DESIGN_ROWS, side="right")) - 1))
        origin, scale, ok = np.empty((hi - lo, 2)), np.empty(hi - lo), np.zeros(hi - lo, np.int8)
        _rings.design(x, y, starts, lo, hi, design, origin, scale, ok)
        fitted = np.flatnonzero(ok)
        base = int(starts[lo])
        for a, b in zip((starts[lo + fitted] - base).tolist(), (starts[lo + fitted + 1] - base).tolist()):
            d = design[a:b]
            scs.append(d.T @ d)
        parts.append((lo + fitted, origin[fitted], scale[fitted]))
        lo = hi
    if not scs:
        return EllipseSums.joined([])
    return EllipseSums(*(np.concatenate(arrays) for arrays in zip(*parts)), np.array(scs))


def _reference_sums(x: np.ndarray, y: np.ndarray, starts: np.ndarray) -> EllipseSums:
    """:func:`ellipse_sums` by numpy alone, set after set (the reference of the compiled rows: the same bits)."""
    x, y = np.ascontiguousarray(x, dtype=float), np.ascontiguousarray(y, dtype=float)
    starts = np.asarray(starts, dtype=np.int64)
    sizes = np.diff(starts)
    big = int(sizes.max()) if len(sizes) else 0
    design = np.empty((big, 6))
    design[:, 5] = 1.0
    running = np.empty(big)
    use, origins, scales, scs = [], [], [], []
    for i in np.flatnonzero(sizes >= 5).tolist():
        a, b = int(starts[i]), int(starts[i + 1])
        n = b - a
        xs, ys = x[a:b], y[a:b]
        if not (np.isfinite(xs).all() and np.isfinite(ys).all()):
            continue
        origin = np.array([np.cumsum(xs, out=running[:n])[-1], np.cumsum(ys, out=running[:n])[-1]]) / n
        cx, cy = xs - origin[0], ys - origin[1]
        scale = float(np.sqrt(np.mean(cx * cx + cy * cy)))
        if not scale > 0:
            continue
        cx /= scale
        cy /= scale
        d = design[:n]
        np.multiply(cx, cx, out=d[:, 0])
        np.multiply(cx, cy, out=d[:, 1])
        np.multiply(cy, cy, out=d[:, 2])
        d[:, 3] = cx
        d[:, 4] = cy
        use.append(i), origins.append(origin), scales.append(scale), scs.append(d.T @ d)
    if not use:
        return EllipseSums.joined([])
    return EllipseSums(np.array(use, np.int64), np.array(origins), np.array(scales), np.array(scs))


def _conditioned(s3: np.ndarray) -> np.ndarray:
    """Whether ``np.linalg.cond(s3) <= 1e12`` for each stacked 3 x 3 scatter matrix of [x, y, 1] (singular
    exactly when the points are collinear; the cutoff is relative: unit RMS data).  The SVD only where a
    cheap bound cannot decide: a Gram matrix's eigenvalues are its singular values, so
    cond <= trace^3 / det (lambda_max <= trace, lambda_min >= det / trace^2), and a bound of 1e10 (the
    determinant's round-off is ~1e-15 trace^3, the SVD's relative error in sigma_min ~1e-16 cond) leaves
    the answer to the SVD's own margin.  Skips the SVD of nearly every set (docs/performance.md 6.5)."""
    a, b, c = s3[:, 0, 0], s3[:, 0, 1], s3[:, 0, 2]
    d, e, f = s3[:, 1, 1], s3[:, 1, 2], s3[:, 2, 2]
    with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
        trace = a + d + f
        det = a * (d * f - e * e) - b * (b * f - e * c) + c * (b * e - d * c)
        sure = (det > 0) & (trace ** 3 <= 1e10 * det)  # False for NaN and inf
    ok = sure.copy()
    rest = np.flatnonzero(~sure)
    if len(rest):
        with np.errstate(invalid="ignore", divide="ignore", over="ignore"):
            ok[rest] = np.linalg.cond(s3[rest]) <= 1e12
    return ok


def ellipses_from_sums(sums: EllipseSums, n_sets: int) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The fits of :func:`fit_ellipses` from the sets' :func:`ellipse_sums` (sets 0 .. n_sets - 1; the
    ones not in ``sums.use`` are NaN): the reduced 3 x 3 eigenproblem and the conic's geometry, each step
    one call on the stacked matrices."""
    centers, axes, angles = np.full((n_sets, 2), np.nan), np.full((n_sets, 2), np.nan), np.full(n_sets, np.nan)
    use, origin, scale = sums.use, sums.origin, sums.scale
    if not len(use):
        return centers, axes, angles
    s1, s2, s3 = (np.ascontiguousarray(part) for part in (sums.sc[:, :3, :3], sums.sc[:, :3, 3:], sums.sc[:, 3:, 3:]))
    ok = _conditioned(s3)
    use, s1, s2, s3, origin, scale = use[ok], s1[ok], s2[ok], s3[ok], origin[ok], scale[ok]
    if len(use) == 0:
        return centers, axes, angles
    t = -np.linalg.solve(s3, np.swapaxes(s2, 1, 2))
    reduced = _C1_INV @ (s1 + s2 @ t)
    finite = np.all(np.isfinite(reduced), axis=(1, 2))
    reduced[~finite] = np.eye(3)
    with np.errstate(invalid="ignore"):
        eigval, eigvec = np.linalg.eig(reduced)
    found = finite & np.all(np.isfinite(eigvec), axis=(1, 2))
    eigvec = np.real(eigvec)
    constraint = 4 * eigvec[:, 0, :] * eigvec[:, 2, :] - eigvec[:, 1, :] ** 2
    admissible = (constraint > 0) & (np.abs(np.imag(eigval)) < 1e-12 * (1 + np.abs(eigval)))
    found &= np.any(admissible, axis=1)
    # exactly one eigenvector satisfies the constraint in theory; with round-off take the one of
    # smallest non-negative eigenvalue (the algebraic residual)
    best = np.argmin(np.where(admissible, np.abs(np.real(eigval)), np.inf), axis=1)
    a1 = np.take_along_axis(eigvec, best[:, None, None], axis=2)[:, :, 0]
    a, b, c = a1.T
    d, e, f = (t @ a1[:, :, None])[:, :, 0].T
    # conic geometry: centre, semi-axes (major first), major-axis angle, in scaled coordinates
    found &= a * c - b * b / 4 > 0
    quad = np.stack([np.stack([a, b / 2], axis=1), np.stack([b / 2, c], axis=1)], axis=1)
    quad[~found] = np.eye(2)
    centre = np.linalg.solve(quad, np.column_stack([-d / 2, -e / 2])[:, :, None])[:, :, 0]
    value_at_center = f + (d * centre[:, 0] + e * centre[:, 1]) / 2
    lam, vec = np.linalg.eigh(quad)
    with np.errstate(invalid="ignore", divide="ignore"):
        squared = -value_at_center[:, None] / lam
        found &= np.all(np.isfinite(squared), axis=1) & np.all(squared > 0, axis=1)
        semi = np.sqrt(squared) * scale[:, None]
    major = np.argmax(semi, axis=1)
    direction = np.take_along_axis(vec, major[:, None, None], axis=2)[:, :, 0]
    angle = np.arctan2(direction[:, 1], direction[:, 0])
    angle = np.where(angle <= -np.pi / 2, angle + np.pi, np.where(angle > np.pi / 2, angle - np.pi, angle))
    centre_out = origin + centre * scale[:, None]
    found &= np.all(np.isfinite(centre_out), axis=1)
    centers[use[found]] = centre_out[found]
    axes[use[found]] = np.sort(semi[found], axis=1)[:, ::-1]
    angles[use[found]] = angle[found]
    return centers, axes, angles
