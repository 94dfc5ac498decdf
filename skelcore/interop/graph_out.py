"""The evaluated curve skeleton as a networkx graph (``Evaluation.to_networkx``): node i is vertex i with
its position and per-vertex values (degree, smoothness (docs/metrics.md 4), radius when known); each edge carries
its length and its samples' boundedness and centeredness (docs/metrics.md 2-3: mean and fraction above the
threshold); ``graph.graph`` holds the overall scores. networkx is imported only here, when asked.
"""

from __future__ import annotations

import numpy as np

__all__ = ["to_networkx"]


def _per_edge(values: np.ndarray, edge: np.ndarray, n_edges: int, threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """Mean of the finite values on each edge and the fraction of its samples above ``threshold``
    (NaN where an edge has no samples; an invalid sample counts as not above)."""
    v = np.asarray(values, dtype=np.float64)
    ok = np.isfinite(v)
    count = np.bincount(edge, minlength=n_edges).astype(float)
    n_ok = np.bincount(edge[ok], minlength=n_edges).astype(float)
    total = np.bincount(edge[ok], weights=v[ok], minlength=n_edges)
    with np.errstate(invalid="ignore", divide="ignore"):
        mean = np.where(n_ok > 0, total / n_ok, np.nan)
        above = np.bincount(edge[ok & (np.where(ok, v, -np.inf) > threshold)], minlength=n_edges) / count
    return mean, np.where(count > 0, above, np.nan)


def to_networkx(ev: "object", *, beta_star: float | None = None, c_star: float | None = None):
    """A ``networkx.Graph`` of the curve skeleton with the local values as attributes (see the module)."""
    try:
        import networkx as nx
    except ImportError:  # pragma: no cover - networkx is in the test and interop extras
        raise ImportError("Evaluation.to_networkx needs networkx: pip install networkx") from None
    cv = ev.curve
    if cv is None:
        raise ValueError("this evaluation has no curve skeleton")
    b_star = ev.params.beta_star if beta_star is None else float(beta_star)
    c_star_ = ev.params.c_star if c_star is None else float(c_star)
    curve = cv.curve
    v, e = curve.vertices, curve.edges
    g = nx.Graph(summary=ev.summary(b_star, c_star_))
    radius = getattr(curve, "radius", None)
    for i in range(len(v)):
        attrs = {"pos": v[i].copy(), "x": float(v[i, 0]), "y": float(v[i, 1]), "z": float(v[i, 2]),
                 "degree": int(cv.vertex_degree[i]), "smoothness": float(cv.vertex_smoothness[i])}
        if radius is not None:
            attrs["radius"] = float(radius[i])
        g.add_node(i, **attrs)
    b_mean, b_frac = _per_edge(cv.sample_boundedness, cv.sample_edge, len(e), b_star)
    c_mean, c_frac = _per_edge(cv.sample_centeredness(b_star), cv.sample_edge, len(e), c_star_)
    n_samples = np.bincount(cv.sample_edge, minlength=len(e))
    lengths = curve.edge_lengths()
    for k, (a, b) in enumerate(e.tolist()):
        g.add_edge(a, b, length=float(lengths[k]), n_samples=int(n_samples[k]),
                   boundedness=float(b_mean[k]), bounded_fraction=float(b_frac[k]),
                   centeredness=float(c_mean[k]), centered_fraction=float(c_frac[k]))
    return g
