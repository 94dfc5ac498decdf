"""The arrays a picture of an Evaluation draws: the cloud, the skeletal points and the curve with
their local values (centeredness after the unbounded rule of docs/metrics.md 3.3, NaN = invalid), both H0 barcodes.

One dict for every picture: compare stores it per job (``jobs/KEY.npz``, float32 coordinates) and
draws its report and figure from it; ``Evaluation.show`` draws the same dict made on the spot.
"""

from __future__ import annotations

from typing import Any

import numpy as np

__all__ = ["drawing_arrays"]


def drawing_arrays(ev: Any) -> dict[str, np.ndarray]:
    """``cloud``, ``skeletal`` + ``skeletal_{metric}``, ``curve_vertices`` / ``curve_edges`` /
    ``curve_samples`` + ``curve_sample_{boundedness,centeredness}``, ``curve_vertex_smoothness``,
    ``cloud_barcode`` / ``skeletal_barcode`` / ``eps_star`` / ``n_bars`` (each only when computed)."""
    f32 = lambda a: np.asarray(a, dtype=np.float32)  # noqa: E731
    out = {"cloud": f32(ev.cloud)}
    b_star = ev.params.beta_star
    if ev.skeletal is not None:
        s = ev.skeletal
        out.update(skeletal=f32(s.points), skeletal_boundedness=f32(s.boundedness),
                   skeletal_centeredness=f32(s.centeredness(b_star)), skeletal_smoothness=f32(s.smoothness))
    if ev.curve is not None:
        c = ev.curve
        out.update(curve_vertices=f32(c.curve.vertices), curve_edges=np.asarray(c.curve.edges, np.int32),
                   curve_samples=f32(c.samples), curve_sample_boundedness=f32(c.sample_boundedness),
                   curve_sample_centeredness=f32(c.sample_centeredness(b_star)),
                   curve_vertex_smoothness=f32(c.vertex_smoothness))
    if ev.topology is not None:
        out.update(cloud_barcode=np.asarray(ev.topology.cloud_barcode, np.float64),
                   skeletal_barcode=np.asarray(ev.topology.skeletal_barcode, np.float64),
                   eps_star=np.array([ev.topology.eps_star]), n_bars=np.array([ev.topology.n_bars]))
    return out
