"""Generate resources/samples/ from analytic shapes (never hand-edited; rerun to regenerate).

Each sample is a cloud, a skeletal point set in pointwise correspondence and a curve skeleton, all
PLY (the curve keeps its ``edge`` element). ``*_skeletal.ply`` is the exact medial projection (the
ground truth: smoothness 1, centeredness as docs/metrics.md 5.6 says); ``*_curve.ply`` is the true axis with a
small seeded jitter of its vertices, so curve smoothness varies a little; the Y shape's junction vertex
has no smoothness value (drawn magenta). When the skeletonizer is
available its output for each cloud is written too (``*_lbc_skeletal.ply``, ``*_lbc_curve.ply``).
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from skelcore import shapes  # noqa: E402
from skelcore.io import write_curve_ply, write_points_ply  # noqa: E402

OUT = ROOT / "resources" / "samples"


def jitter(points: np.ndarray, scale: float, rng: np.random.Generator) -> np.ndarray:
    return points + rng.normal(scale=scale, size=points.shape)


def main() -> None:
    OUT.mkdir(parents=True, exist_ok=True)
    rng = np.random.default_rng(2026)
    samples = {
        "cylinder": shapes.cylinder(3000, radius=0.5, length=4.0, seed=1),
        "torus": shapes.torus(3000, R=1.0, r=0.3, seed=2),
        "yshape": shapes.y_shape(4000, radius=0.25, arm=2.0, seed=3),
    }
    for name, shape in samples.items():
        scale = 0.0005 * float(np.ptp(shape.cloud, axis=0).max())
        skeletal = shape.skeletal
        verts = jitter(shape.curve_vertices, scale / 2, rng)
        write_points_ply(OUT / f"{name}_cloud.ply", shape.cloud)
        write_points_ply(OUT / f"{name}_skeletal.ply", skeletal)
        write_curve_ply(OUT / f"{name}_curve.ply", verts, shape.curve_edges)
        print(f"{name}: {len(shape.cloud)} points, curve {len(verts)} vertices / {len(shape.curve_edges)} edges")
        try:
            from skelcore.skeleton import skeletonize
        except ImportError:
            continue
        skel_pts, curve = skeletonize(shape.cloud)
        write_points_ply(OUT / f"{name}_lbc_skeletal.ply", skel_pts)
        write_curve_ply(OUT / f"{name}_lbc_curve.ply", curve.vertices, curve.edges)
        print(f"{name}: skeletonized, curve {curve.n_vertices} vertices / {curve.n_edges} edges")


if __name__ == "__main__":
    main()
