"""Comparison of a curve skeleton with a reference (ground-truth) curve skeleton (SkelScope's own,
not the paper's; docs/metrics.md "Reference comparison").

Both curves are sampled densely (every tau / 2 along each edge); Chamfer is the mean of the two
mean nearest-sample distances, Hausdorff the larger of the two maxima; precision is the fraction
of our samples within tau of the reference, recall the reverse, F1 their harmonic mean. The graph
counts (junctions: degree >= 3, endpoints: degree 1, connected components, independent cycles
E - V + C) are given for both as ``[ours, reference]``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from ..correspondence import densify_curve
from ..curve import CurveSkeleton

__all__ = ["ReferenceComparison", "compare_with_reference", "graph_counts"]

_MAX_SAMPLES = 200_000


@dataclass
class ReferenceComparison:
    chamfer: float
    hausdorff: float
    precision: float
    recall: float
    f1: float
    junctions: tuple[int, int]
    endpoints: tuple[int, int]
    components: tuple[int, int]
    cycles: tuple[int, int]
    tau: float

    def to_dict(self) -> dict:
        return {
            "chamfer": self.chamfer, "hausdorff": self.hausdorff, "precision": self.precision,
            "recall": self.recall, "f1": self.f1, "junctions": list(self.junctions),
            "endpoints": list(self.endpoints), "components": list(self.components),
            "cycles": list(self.cycles), "tau": self.tau,
        }  # fmt: skip


def graph_counts(curve: CurveSkeleton) -> dict[str, int]:
    """Junctions (degree >= 3), endpoints (degree 1), connected components, independent cycles."""
    n = curve.n_vertices
    deg = curve.degrees()
    e = curve.edges
    adj = coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)) if len(e) else coo_matrix((n, n))
    n_comp = int(connected_components(adj, directed=False)[0])
    return {
        "junctions": int(np.count_nonzero(deg >= 3)),
        "endpoints": int(np.count_nonzero(deg == 1)),
        "components": n_comp,
        "cycles": int(len(e) - n + n_comp),
    }


def _samples(curve: CurveSkeleton, step: float) -> np.ndarray:
    total = float(curve.edge_lengths().sum()) if curve.n_edges else 0.0
    step = max(step, total / _MAX_SAMPLES, 1e-12)
    pts, _ = densify_curve(curve, step)
    isolated = np.setdiff1d(np.arange(curve.n_vertices), curve.edges.ravel())
    return np.vstack([pts, curve.vertices[isolated]]) if curve.n_edges else curve.vertices.copy()


def compare_with_reference(ours: CurveSkeleton, reference: CurveSkeleton, tau: float) -> ReferenceComparison:
    """Compare two curves given in the same (normalized) frame; ``tau`` is the match distance."""
    a = _samples(ours, tau / 2.0)
    b = _samples(reference, tau / 2.0)
    d_ab, _ = cKDTree(b).query(a, k=1, workers=-1)
    d_ba, _ = cKDTree(a).query(b, k=1, workers=-1)
    precision = float(np.mean(d_ab <= tau))
    recall = float(np.mean(d_ba <= tau))
    f1 = 0.0 if precision + recall == 0 else 2 * precision * recall / (precision + recall)
    ga, gb = graph_counts(ours), graph_counts(reference)
    return ReferenceComparison(
        chamfer=float((d_ab.mean() + d_ba.mean()) / 2.0),
        hausdorff=float(max(d_ab.max(), d_ba.max())),
        precision=precision,
        recall=recall,
        f1=float(f1),
        junctions=(ga["junctions"], gb["junctions"]),
        endpoints=(ga["endpoints"], gb["endpoints"]),
        components=(ga["components"], gb["components"]),
        cycles=(ga["cycles"], gb["cycles"]),
        tau=float(tau),
    )
