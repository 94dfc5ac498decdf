"""What an evaluation found out about its scan, and the two warnings it can give (docs/metrics.md 6):
``open_surface`` (openings that change boundedness) and ``outliers`` (stray points).

:class:`ScanReport` is plain JSON data (the ``scan`` block of ``evaluate --json``): positions and lengths
in the cloud's units, rows of the evaluated cloud (``Evaluation.cloud``) except ``outliers.rows``, which
are rows of the cloud as given (before ``--remove-outliers``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

from ..diagnostics.trust_warning import TrustWarning
from .prepare import Strays

__all__ = ["ScanReport", "outliers_warning", "open_surface_warning", "thin_parts_warning", "sparse_boundedness_warning"]


@dataclass
class ScanReport:
    """Viewpoints, stray points and openings of one evaluation (None / empty: not asked, not looked for)."""

    viewpoints: list[list[float]] = field(default_factory=list)  # sensor positions (viewpoint-aware scores)
    outliers: dict[str, Any] | None = None  # Outliers.to_dict() of the cloud as given
    outliers_removed: bool = False  # --remove-outliers: evaluated without them
    skeletal_rows_removed: int = 0  # skeletal rows dropped with their cloud rows (pointwise, index)
    openings: list[dict[str, Any]] | None = None  # Opening.to_dict() + rows, capped, refused
    cap_points: int = 0  # points added by --cap-openings (boundedness only)
    escaping: dict[str, float | None] = field(default_factory=dict)  # column -> share unbounded through openings
    thin_parts: dict[str, Any] | None = None  # openings.thin_parts(): parts too thin for their sampling
    sparse: dict[str, float] = field(default_factory=dict)  # column -> share unbounded where sampled sparsely
    timings: dict[str, float] = field(default_factory=dict)

    def to_dict(self) -> dict[str, Any]:
        return {
            "viewpoints": [list(map(float, v)) for v in self.viewpoints],
            "outliers": self.outliers,
            "outliers_removed": bool(self.outliers_removed),
            "skeletal_rows_removed": int(self.skeletal_rows_removed),
            "openings": self.openings,
            "cap_points": int(self.cap_points),
            "escaping": dict(self.escaping),
            "thin_parts": self.thin_parts,
            "sparse": dict(self.sparse),
            "timings_s": {k: round(float(v), 6) for k, v in self.timings.items()},
        }

    @classmethod
    def from_dict(cls, doc: dict[str, Any]) -> "ScanReport":
        return cls(
            viewpoints=[list(map(float, v)) for v in doc.get("viewpoints") or []],
            outliers=doc.get("outliers"),
            outliers_removed=bool(doc.get("outliers_removed", False)),
            skeletal_rows_removed=int(doc.get("skeletal_rows_removed", 0)),
            openings=doc.get("openings"),
            cap_points=int(doc.get("cap_points", 0)),
            escaping=dict(doc.get("escaping") or {}),
            thin_parts=doc.get("thin_parts"),
            sparse=dict(doc.get("sparse") or {}),
            timings={k: float(v) for k, v in (doc.get("timings_s") or {}).items()},
        )

    def opening_rows(self) -> list[np.ndarray]:
        """The rim rows of every opening (rows of the evaluated cloud), for drawing them."""
        return [np.asarray(o["rows"], dtype=np.int64) for o in self.openings or []]


def outliers_warning(strays: Strays) -> TrustWarning:
    """``outliers``: their count and what they do to the normalization (docs/metrics.md 0)."""
    found = strays.cloud
    moves = []
    if abs(found.scale_ratio - 1.0) > 1e-3:
        moves.append(f"make the bounding box {found.scale_ratio:.3g} x as large")
    if found.centre_shift > 1e-3:
        moves.append(f"move its centre by {found.centre_shift:.3g} of its size")
    what = ("they " + " and ".join(moves) + ", so every metric runs in another normalization"
            if moves else "they stay inside its bounding box but add bars to the topology")
    n_skel = len(strays.skeletal_rows)
    skel = (f"{n_skel} skeletal point{'s' if n_skel != 1 else ''} far from every other skeletal point"
            if n_skel else "")
    if found.count:
        head = (f"{found.count} stray point{'s' if found.count != 1 else ''} of {found.n_points} in the cloud (far "
                f"from every other point by the statistical and the radius test): {what}")
        head += f"; and {skel}" if skel else ""
    else:
        head = skel + " (the radius test, the cloud's spacing as yardstick)"
    return TrustWarning("outliers", f"{head}; --remove-outliers evaluates without them")


def open_surface_warning(kinds: list[str], largest: float, shares: dict[str, float]) -> TrustWarning:
    """``open_surface``: the openings, and the share of each skeleton's elements that are unbounded only
    because their rays leave through them."""
    ends, sides = kinds.count("end"), kinds.count("side")
    parts = [f"{ends} open tube end{'s' if ends != 1 else ''}"] if ends else []
    if sides:
        parts.append(f"{sides} missing side{'s' if sides != 1 else ''}")
    size = f", the largest {largest:.3g} local radii wide" if np.isfinite(largest) else ""
    names = {"skeletal": "skeletal points", "curve": "curve samples"}
    through = " and ".join(f"{share:.0%} of the {names[col]}" for col, share in shares.items())
    return TrustWarning(
        "open_surface",
        f"the cloud is not a closed surface ({', '.join(parts)}{size}): {through} are unbounded only because their "
        "rays leave through the openings (the paper's boundedness assumes a closed surface); give the sensor "
        "position with --viewpoint X Y Z, or close small flat openings with --cap-openings",
    )


def thin_parts_warning(thin: dict[str, Any]) -> TrustWarning:
    """``thin_parts``: parts of the cloud sampled too thinly to resolve (:func:`.openings.thin_parts`),
    where and how many; it switches no other verdict off (docs/metrics.md 6.1)."""
    lo, hi = thin["box"]
    parts = thin["parts"]
    return TrustWarning(
        "thin_parts",
        f"{parts} part{'s' if parts != 1 else ''} of the shape {'are' if parts != 1 else 'is'} sampled too thinly to "
        f"resolve (fewer spacings across than a surface needs; {thin['points']} boundary points, "
        f"{thin['share']:.1%} of the cloud, from ({', '.join(f'{x:.4g}' for x in lo)}) to "
        f"({', '.join(f'{x:.4g}' for x in hi)})): their gaps are not taken for openings, and boundedness there "
        "counts rays through the gaps between samples; sample more densely",
    )


def sparse_boundedness_warning(shares: dict[str, float], ratio: float) -> TrustWarning:
    """``sparse_boundedness``: the share of each skeleton's elements unbounded where the cloud is sampled
    more than ``ratio`` x as sparsely as its median (docs/metrics.md 6.1)."""
    names = {"skeletal": "skeletal points", "curve": "curve samples"}
    which = " and ".join(f"{share:.0%} of the {names[col]}" for col, share in shares.items())
    return TrustWarning(
        "sparse_boundedness",
        f"{which} are unbounded where the cloud is sampled more than {ratio:g} x as sparsely as its median: "
        "their rays may pass between the samples, so boundedness there measures the sampling, not the skeleton; "
        "--density-aware (boundedness_density_aware) casts them also against points filled into the sparse parts",
    )
