"""The broken hammer (docs/repair.md "A thick part's fill"): the real hammer scan
(resources/scans/hammer_4096.ply) with cao's curve cut to the middle of its handle (no head, no far
end: pc-skeletor's truncated output, as in scripts/make_screenshots.py) and a two-edge twig from the
handle out through its side (a spur that leaves the shape)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]


def broken_hammer_curve():
    """(the hammer's cloud, the broken curve as a CurveSkeleton)."""
    from skelcore.curve import CurveSkeleton
    from skelcore.io import load_cloud
    from skelcore.skeleton import skeletonize

    cloud = load_cloud(str(ROOT / "resources" / "scans" / "hammer_4096.ply"))
    _skeletal, curve = skeletonize(cloud, method="cao")
    y = curve.vertices[:, 1]  # the handle runs along y from -199 to about 80, the head beyond
    keep = (y > -60) & (y < 85)
    new = -np.ones(len(keep), np.int64)
    new[keep] = np.arange(int(keep.sum()))
    v, e = curve.vertices[keep], new[curve.edges[keep[curve.edges].all(axis=1)]]
    mid = int(np.argmin(np.abs(v[:, 1] - 10.0)))  # the handle is about 10 across: out to 30 sideways
    v = np.vstack([v, v[mid] + [0.0, 0.0, 12.0], v[mid] + [0.0, 0.0, 30.0]])
    e = np.vstack([e, [[mid, len(v) - 2], [len(v) - 2, len(v) - 1]]])
    return cloud, CurveSkeleton.from_raw(v, e)
