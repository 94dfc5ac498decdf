"""Direct least-squares ellipse fit (Fitzgibbon, Pilu & Fisher 1999) in the numerically stable
form of Halir & Flusser (1998): the cross-section centre and semi-axes l_a, l_b of curve
centeredness (paper Eq. 11, ``eq.curve_point_centeredness``, and its remark; SPEC 3).  The paper
prefers a fitted ellipse to the barycentre as the centre of a partly sampled cross-section.
"""

from __future__ import annotations

import numpy as np

__all__ = ["fit_ellipse"]

# C1^-1 for the constraint 4ac - b^2 = 1 on (a, b, c): C1 = [[0, 0, 2], [0, -1, 0], [2, 0, 0]]
_C1_INV = np.array([[0.0, 0.0, 0.5], [0.0, -1.0, 0.0], [0.5, 0.0, 0.0]])


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
    if len(xy) < 5 or not np.all(np.isfinite(xy)):
        return None
    origin = xy.mean(axis=0)
    centred = xy - origin
    scale = float(np.sqrt(np.mean(np.einsum("ij,ij->i", centred, centred))))
    if not scale > 0:
        return None
    x, y = (centred / scale).T

    d1 = np.column_stack([x * x, x * y, y * y])
    d2 = np.column_stack([x, y, np.ones_like(x)])
    s1 = d1.T @ d1
    s2 = d1.T @ d2
    s3 = d2.T @ d2
    # s3 is singular exactly when the points are collinear; the cutoff is relative (unit RMS data)
    if np.linalg.cond(s3) > 1e12:
        return None
    t = -np.linalg.solve(s3, s2.T)
    reduced = _C1_INV @ (s1 + s2 @ t)
    with np.errstate(invalid="ignore"):
        eigval, eigvec = np.linalg.eig(reduced)
    if not np.all(np.isfinite(eigvec)):
        return None
    eigvec = np.real(eigvec)
    constraint = 4 * eigvec[0] * eigvec[2] - eigvec[1] ** 2
    ok = np.flatnonzero((constraint > 0) & (np.abs(np.imag(eigval)) < 1e-12 * (1 + np.abs(eigval))))
    if len(ok) == 0:
        return None
    # exactly one eigenvector satisfies the constraint in theory; with round-off take the one of
    # smallest non-negative eigenvalue (the algebraic residual)
    best = ok[np.argmin(np.abs(np.real(eigval[ok])))]
    a1 = eigvec[:, best]
    a, b, c = a1
    d, e, f = t @ a1
    return _conic_geometry(a, b, c, d, e, f, origin, scale)


def _conic_geometry(a: float, b: float, c: float, d: float, e: float, f: float, origin: np.ndarray, scale: float):
    """Centre, semi-axes (major first) and major-axis angle of an ellipse conic in scaled coordinates."""
    quad = np.array([[a, b / 2], [b / 2, c]])
    det = a * c - b * b / 4
    if not det > 0:
        return None
    center = np.linalg.solve(quad, [-d / 2, -e / 2])
    value_at_center = f + (d * center[0] + e * center[1]) / 2
    lam, vec = np.linalg.eigh(quad)
    with np.errstate(invalid="ignore", divide="ignore"):
        squared = -value_at_center / lam
    if not np.all(np.isfinite(squared)) or not np.all(squared > 0):
        return None
    axes = np.sqrt(squared) * scale
    major = int(np.argmax(axes))
    direction = vec[:, major]
    angle = float(np.arctan2(direction[1], direction[0]))
    if angle <= -np.pi / 2:
        angle += np.pi
    elif angle > np.pi / 2:
        angle -= np.pi
    center_out = origin + center * scale
    if not np.all(np.isfinite(center_out)):
        return None
    return center_out, np.sort(axes)[::-1], angle
