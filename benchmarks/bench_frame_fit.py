"""The ``frame`` suggestion: the bounding-box rule against the refined fit (docs/diagnostics.md "Frame").

A skeleton in voxel coordinates of a grid laid over the cloud (pitch = the longest side / 100, voxel
(0, 0, 0) two voxels below the cloud's min corner, coordinates rounded to voxel indices, as kimimaro
writes them): the hammer scan's cao curve and the exact and cao curves of the generated shapes
(x 30). For each: the bounding-box suggestion ("old": boxes centred, scaled x 1 / 0.85 / 0.7, the most
bounded), the refined fit ("new": ``skelcore.diagnostics.trust``), and the grid's own mapping: scale / the grid's pitch,
the largest point error (share of the cloud's diagonal), the curve's boundedness, centeredness and
completeness under each, and the seconds the evaluation took.

    PYTHONPATH=. .venv/bin/python benchmarks/bench_frame_fit.py
"""

from __future__ import annotations

import re
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import skelcore  # noqa: E402
from skelcore import shapes  # noqa: E402
from skelcore.curve import CurveSkeleton  # noqa: E402
from skelcore.diagnostics import missing_parts  # noqa: E402
from skelcore.geometry import Normalization  # noqa: E402
from skelcore.metrics.boundedness import boundedness  # noqa: E402
from skelcore.params import Params  # noqa: E402
from skelcore.diagnostics.trust import bbox_transform  # noqa: E402

SUGGESTED = re.compile(r"--skeleton-scale ([-\d.e+]+) --skeleton-offset ([-\d.e+]+) ([-\d.e+]+) ([-\d.e+]+)\)")


def old_suggestion(cloud, samples, p):
    """The bounding-box rule: the most bounded of the bounding-box matches x 1, 0.85, 0.7."""
    norm = Normalization.from_cloud(cloud)
    c = norm.apply(cloud)
    s0, _ = bbox_transform(cloud, samples)
    cc = (cloud.min(axis=0) + cloud.max(axis=0)) / 2
    cs = (samples.min(axis=0) + samples.max(axis=0)) / 2
    best, best_s = -1.0, s0
    for f in (1.0, 0.85, 0.7):
        b = float(np.mean(boundedness(c, norm.apply((samples - cs) * s0 * f + cc), params=p) > p.beta_star))
        if b > best:
            best, best_s = b, s0 * f
    return best_s, cc - best_s * cs


def scores(cloud, vox, edges, s, off):
    ev = skelcore.evaluate(cloud, curve=(vox * s + off, edges))
    norm = Normalization.from_cloud(cloud)
    mp = missing_parts(norm.apply(cloud), CurveSkeleton.from_raw(norm.apply(vox * s + off), edges))
    sm = ev.summary()
    return sm["boundedness"]["curve"], sm["centeredness"]["curve"], mp.completeness, mp.incomplete


def case(name, cloud, curve, p):
    h = float(np.ptp(cloud, axis=0).max()) / 100
    origin = cloud.min(axis=0) - 2 * h
    vox = np.round((curve.vertices - origin) / h)
    t0 = time.perf_counter()
    ev = skelcore.evaluate(cloud, curve=(vox, curve.edges))
    dt = time.perf_counter() - t0
    diag = float(np.linalg.norm(np.ptp(cloud, axis=0)))
    rows = {"grid": (h, origin)}
    rows["old"] = old_suggestion(cloud, ev.curve.samples, p)
    frame = [w for w in ev.warnings if w.code == "frame"]
    m = SUGGESTED.search(frame[0].message) if frame else None
    if m:
        rows["new"] = (float(m.group(1)), np.array([float(m.group(i)) for i in (2, 3, 4)]))
    for label, (s, off) in rows.items():
        err = float(np.abs(vox * s + off - (vox * h + origin)).max()) / diag
        b, c, comp, inc = scores(cloud, vox, curve.edges, s, off)
        flag = " (incomplete)" if inc else ""
        took = f"{dt:.1f}" if label == "new" else ""
        print(f"| {name} | {label} | {s / h:.3f} | {err:.4f} | {b:.3f} | {c:.3f} | {comp:.3f}{flag} | {took} |")
    if not m:
        print(f"| {name} | new | none proposed | | | | | {dt:.1f} |")


def main() -> None:
    p = Params()
    print("| case | mapping | scale / pitch | max error / diag | bounded | centred | completeness | eval s |")
    print("|---|---|---|---|---|---|---|---|")
    cloud = skelcore.load_cloud(ROOT / "resources" / "scans" / "hammer_4096.ply")
    _, curve = skelcore.skeletonize(cloud, method="cao")
    case("hammer cao", cloud, curve, p)
    for name, sh in (("T", shapes.t_shape(6000)), ("Y", shapes.y_shape(6000)), ("tree3", shapes.tree3(8000)),
                     ("torus", shapes.torus(4096)), ("genus2", shapes.genus2(8000)), ("cylinder", shapes.cylinder(4096))):
        cloud = sh.cloud * 30
        case(f"{name} exact", cloud, CurveSkeleton.from_raw(sh.curve_vertices * 30, sh.curve_edges), p)
        _, curve = skelcore.skeletonize(cloud, method="cao")
        case(f"{name} cao", cloud, curve, p)


if __name__ == "__main__":
    main()
