"""Branches that run along the shape's wall instead of its axis -> ``along_surface``
(docs/diagnostics.md "Along the surface").

A TEASAR-like branch hugging the wall is inside (no ``outside``), explains the cloud (no
``incomplete``) and is real (no ``spurious_branches``); only the paper's curve centeredness falls
(Eq. 11, docs/metrics.md 3.2: on a round section a sample lies c x r from the wall). This module reads
the evaluation's raw centeredness and boundedness per curve sample and searches the cloud only for the
junctions' local radii. A bounded sample with a centeredness above 0 (0 is Eq. 11's clip, no measure),
beyond ``surface_junction_radii`` of its branch's junctions, is off axis below
``surface_max_centeredness``; a branch is flagged when enough of its samples and length are off axis.
Where Eq. 11's slab is thicker than ``surface_slab_radii`` local radii (a traced neuron) its section
says nothing of the axis: no branch is judged (``unchecked``). The rule's details are in the docs.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..geometry import group_min_median_max
from ..metrics.curve_sampling import CurveSamples
from ..params import Params
from .branches import Branches
from .trust_warning import TrustWarning

__all__ = ["SurfaceRuns", "find_along_surface"]


@dataclass
class SurfaceRuns:
    """Where the curve runs along the surface.

    sample_off : (S,) bool per curve sample: off axis (bounded, centeredness above 0 and below the
    threshold, beyond its junctions' balls). branch_samples, branch_off : (B,) per branch its samples
    judged and those off axis; branch_length : (B,) the off-axis samples' stretches (normalized
    units); branch_centeredness : (B,) the median centeredness of its off-axis samples (NaN where
    none). radius : the local radius the lengths are measured in. flagged : the branches flagged.
    vertex_flag : (V,) bool, the flagged branches' vertices.
    """

    sample_off: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    branch_samples: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    branch_off: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    branch_length: np.ndarray = field(default_factory=lambda: np.zeros(0))
    branch_centeredness: np.ndarray = field(default_factory=lambda: np.zeros(0))
    radius: float = 0.0
    flagged: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    vertex_flag: np.ndarray = field(default_factory=lambda: np.zeros(0, bool))
    slab_radii: float = 0.0
    params: Params = field(default_factory=Params)

    @property
    def unchecked(self) -> str | None:
        """Why no branch was judged (the slab thicker than the parts), or None."""
        if not self.slab_radii > self.params.surface_slab_radii:
            return None
        return (f"the centeredness slab's half ({self.slab_radii:.2g} local radii) is thicker than surface_slab_radii = "
                f"{self.params.surface_slab_radii:g}: its sections are stretches of the parts, not cross-sections")

    @property
    def branch_radii(self) -> np.ndarray:
        """The off-axis length per branch in local radii (NaN when no radius is known)."""
        return self.branch_length / self.radius if self.radius > 0 else np.full(len(self.branch_length), np.nan)

    def sample_flag(self, sample_branch: np.ndarray | None) -> np.ndarray | None:
        """Per curve sample: on a flagged branch and off axis."""
        if sample_branch is None or len(sample_branch) != len(self.sample_off):
            return None
        return self.sample_off & np.isin(sample_branch, self.flagged)

    def warnings(self) -> list[TrustWarning]:
        if not len(self.flagged):
            return []
        radii = self.branch_radii
        worst = int(self.flagged[np.argmax(self.branch_length[self.flagged])])
        many = len(self.flagged) > 1
        length = f" for {radii[worst]:.2g} local radii" if np.isfinite(radii[worst]) else ""
        head = (f"{len(self.flagged)} branches run along the surface, the longest branch {worst}" if many
                else f"branch {worst} runs along the surface")
        return [TrustWarning(
            "along_surface",
            f"{head}{length} ({self.branch_centeredness[worst]:.2g} cross-section radii from the wall, median)",
        )]  # fmt: skip

    def to_dict(self) -> dict:
        radii = self.branch_radii
        return {"branches": [{"id": int(b), "radii": float(radii[b]) if np.isfinite(radii[b]) else None,
                              "centeredness": float(self.branch_centeredness[b]),
                              "samples_off": int(self.branch_off[b]), "samples": int(self.branch_samples[b])}
                             for b in self.flagged],
                "radius": float(self.radius), "slab_radii": float(self.slab_radii) if np.isfinite(self.slab_radii) else None}


def _stretches(curve: CurveSkeleton, samples: CurveSamples) -> np.ndarray:
    """The length each sample stands for: its edge's length over the edge's sample count."""
    edge = np.asarray(samples.edge, np.int64)
    if not len(edge):
        return np.zeros(0)
    per_edge = np.bincount(edge, minlength=len(curve.edges))
    return curve.edge_lengths()[edge] / per_edge[edge]


def _near_junction(curve: CurveSkeleton, branches: Branches, samples: CurveSamples, sample_branch: np.ndarray,
                   cloud_tree: cKDTree, factor: float) -> np.ndarray:
    """Per sample: within ``factor`` x its junction's distance to the cloud of one of its branch's
    junction ends (only the junctions are looked up in the cloud)."""
    near = np.zeros(len(sample_branch), bool)
    ends, deg = branches.ends, branches.end_degrees
    junctions = np.unique(ends[deg >= 3]) if len(ends) else np.zeros(0, np.int64)
    if not len(junctions) or cloud_tree.n == 0:
        return near
    rj = np.zeros(curve.n_vertices)
    rj[junctions] = cloud_tree.query(np.asarray(curve.vertices, float)[junctions])[0]
    on = sample_branch >= 0
    pts = np.asarray(samples.points, float)[on]
    for side in (0, 1):
        j = ends[sample_branch[on], side]
        is_junction = deg[sample_branch[on], side] >= 3
        dist = np.linalg.norm(pts - np.asarray(curve.vertices, float)[j], axis=1)
        near[np.flatnonzero(on)[is_junction & (dist < factor * rj[j])]] = True
    return near


def find_along_surface(curve: CurveSkeleton, branches: Branches, samples: CurveSamples | None,
                       sample_centeredness: np.ndarray | None, sample_boundedness: np.ndarray | None,
                       cloud_tree: cKDTree, radius: float, params: Params = Params()) -> SurfaceRuns:
    """The branches running along the surface (normalized inputs, docs/metrics.md 0).
    ``sample_centeredness``: the raw curve centeredness per sample (Eq. 11, before the unbounded rule);
    ``sample_boundedness``: per sample; ``radius``: the local radius the lengths are given in."""
    nb, nv = len(branches), curve.n_vertices
    sb = branches.sample_branch
    half = 0.5 * params.slab_factor * float(np.linalg.norm(cloud_tree.maxes - cloud_tree.mins)) if cloud_tree.n else 0.0
    slab_radii = half / radius if radius > 0 else np.inf
    if (samples is None or sample_centeredness is None or sample_boundedness is None or sb is None
            or len(sb) != len(sample_centeredness) or not len(sb) or slab_radii > params.surface_slab_radii):
        return SurfaceRuns(branch_samples=np.zeros(nb, np.int64), branch_off=np.zeros(nb, np.int64),
                           branch_length=np.zeros(nb), branch_centeredness=np.full(nb, np.nan),
                           radius=float(radius), vertex_flag=np.zeros(nv, bool), slab_radii=float(slab_radii),
                           params=params)
    c = np.asarray(sample_centeredness, float)
    beta = np.asarray(sample_boundedness, float)
    sb = np.asarray(sb, np.int64)
    valid = (sb >= 0) & np.isfinite(c) & (c > 0) & (beta > params.beta_star)
    valid &= ~_near_junction(curve, branches, samples, sb, cloud_tree, params.surface_junction_radii)
    off = valid & (c < params.surface_max_centeredness)
    n_valid = np.bincount(sb[valid], minlength=nb)
    n_off = np.bincount(sb[off], minlength=nb)
    length = np.bincount(sb[off], weights=_stretches(curve, samples)[off], minlength=nb)
    med = group_min_median_max(c[off], sb[off], nb)[1]
    with np.errstate(invalid="ignore", divide="ignore"):
        share = np.where(n_valid > 0, n_off / np.maximum(n_valid, 1), 0.0)
    enough = length >= params.surface_min_radii * radius if radius > 0 else np.ones(nb, bool)
    flagged = np.flatnonzero((n_off >= params.surface_min_samples) & (share >= params.surface_min_share) & enough)
    eb = np.asarray(branches.edge_branch, np.int64)
    vflag = np.zeros(nv, bool)
    if len(eb) and len(flagged):
        e = np.asarray(curve.edges, np.int64)[np.isin(eb, flagged)]
        vflag[e.ravel()] = True
    return SurfaceRuns(sample_off=off, branch_samples=n_valid.astype(np.int64), branch_off=n_off.astype(np.int64),
                       branch_length=length, branch_centeredness=med, radius=float(radius),
                       flagged=flagged.astype(np.int64), vertex_flag=vflag, slab_radii=float(slab_radii),
                       params=params)
