"""An Evaluation as a pandas DataFrame (``Evaluation.to_frame``): one row per element with every local
value (NaN = invalid, docs/metrics.md 5.5) and the flags the overall scores count (docs/metrics.md 2-4), so a notebook can
filter, group and plot without knowing SkelScope's arrays. pandas is imported only here, when asked.
"""

from __future__ import annotations

import numpy as np

__all__ = ["FRAME_KINDS", "frame_columns", "to_frame"]

#: the ``kind`` argument of :func:`to_frame`
FRAME_KINDS = ("skeletal", "curve_samples", "curve_vertices", "cloud")


def _flags(values: np.ndarray, threshold: float) -> tuple[np.ndarray, np.ndarray]:
    """(value > threshold, value is valid): NaN is never above a threshold."""
    v = np.asarray(values, dtype=np.float64)
    with np.errstate(invalid="ignore"):
        return v > threshold, np.isfinite(v)


def frame_columns(ev: "object", kind: str, beta_star: float | None = None,
                  c_star: float | None = None) -> dict[str, np.ndarray]:
    """The columns of :func:`to_frame` as numpy arrays (ordered), for callers without pandas."""
    if kind not in FRAME_KINDS:
        raise ValueError(f"kind must be one of {', '.join(FRAME_KINDS)}, got {kind!r}")
    b_star = ev.params.beta_star if beta_star is None else float(beta_star)
    c_star_ = ev.params.c_star if c_star is None else float(c_star)
    if kind == "skeletal":
        s = ev.skeletal
        if s is None:
            raise ValueError("this evaluation has no skeletal point set")
        c = s.centeredness(b_star)
        bounded, b_valid = _flags(s.boundedness, b_star)
        centered, c_valid = _flags(c, c_star_)
        cols = {"index": np.arange(len(s.points)), "x": s.points[:, 0], "y": s.points[:, 1], "z": s.points[:, 2],
                "boundedness": s.boundedness, "centeredness": c, "centeredness_raw": s.centeredness_raw,
                "smoothness": s.smoothness, "bounded": bounded, "centered": centered,
                "boundedness_valid": b_valid, "centeredness_valid": c_valid,
                "smoothness_valid": np.isfinite(s.smoothness)}
        if s.index is not None:
            cols["cloud_row"] = np.asarray(s.index)
        return cols
    if kind == "cloud":
        cols = {"index": np.arange(len(ev.cloud))}
        for name, values in ev.cloud_columns().items():
            cols[name] = values.astype(bool) if name.startswith("covered_") else values
        return cols
    cv = ev.curve
    if cv is None:
        raise ValueError("this evaluation has no curve skeleton")
    if kind == "curve_samples":
        c = cv.sample_centeredness(b_star)
        bounded, b_valid = _flags(cv.sample_boundedness, b_star)
        centered, c_valid = _flags(c, c_star_)
        return {"sample": np.arange(len(cv.samples)), "edge": cv.sample_edge, "t": cv.sample_t,
                "x": cv.samples[:, 0], "y": cv.samples[:, 1], "z": cv.samples[:, 2],
                "boundedness": cv.sample_boundedness, "centeredness": c,
                "centeredness_raw": cv.sample_centeredness_raw, "bounded": bounded, "centered": centered,
                "boundedness_valid": b_valid, "centeredness_valid": c_valid}
    v = cv.curve.vertices
    cols = {"vertex": np.arange(len(v)), "x": v[:, 0], "y": v[:, 1], "z": v[:, 2], "degree": cv.vertex_degree,
            "smoothness": cv.vertex_smoothness, "smoothness_valid": np.isfinite(cv.vertex_smoothness)}
    if getattr(cv.curve, "radius", None) is not None:
        cols["radius"] = cv.curve.radius
    return cols


def to_frame(ev: "object", kind: str = "skeletal", *, beta_star: float | None = None, c_star: float | None = None):
    """A ``pandas.DataFrame`` of one kind of element: ``"skeletal"`` (points: boundedness, centeredness
    after the unbounded -> 0 rule of docs/metrics.md 3.3, its raw value, smoothness, the ``bounded`` / ``centered`` flags
    at beta* / c*, validity), ``"curve_samples"`` (the same per sample, with its edge and t),
    ``"curve_vertices"`` (degree, smoothness, radius when known) or ``"cloud"`` (coverage gaps, the
    reverse correspondence's row). Thresholds default to the evaluation's params."""
    try:
        import pandas as pd
    except ImportError:  # pragma: no cover - pandas is in the test and interop extras
        raise ImportError("Evaluation.to_frame needs pandas: pip install pandas") from None
    return pd.DataFrame(frame_columns(ev, kind, beta_star, c_star))
