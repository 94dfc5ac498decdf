"""The counts of docs/diagnostics.md "Along the surface": each case of a benchmark folder (``skelcore
bench make DIR``, ``--suite real``) evaluated with its exact reference curve, and with that curve's
every vertex moved ``--offsets`` of its radius towards the wall (a fixed direction made perpendicular
to the curve's tangent at the vertex); one line per run (``along_surface`` fired or not, the slab's
half in local radii, "not judged" when it is too thick), then the fired counts per offset.

    python scripts/surface_counts.py DIR [--cases GLOB] [--offsets 0,0.2,0.6]
"""

from __future__ import annotations

import argparse
import glob
import os

import numpy as np

from skelcore import evaluate
from skelcore.benchmark.skeleton_defects import vertex_tangents
from skelcore.curve import CurveSkeleton
from skelcore.io.loaders import load_cloud, load_curve

_TOWARDS = np.array([0.31, 0.83, 0.47]) / np.linalg.norm([0.31, 0.83, 0.47])


def moved(curve: CurveSkeleton, share: float) -> CurveSkeleton:
    """``curve`` with each vertex moved ``share`` x its radius perpendicular to its tangent."""
    if share == 0:
        return curve
    v, e, r = np.asarray(curve.vertices, float), np.asarray(curve.edges), np.asarray(curve.radius, float)
    t = vertex_tangents(v, e)
    p = _TOWARDS - (t @ _TOWARDS)[:, None] * t
    p /= np.maximum(np.linalg.norm(p, axis=1, keepdims=True), 1e-12)
    return CurveSkeleton.from_raw(v + share * r[:, None] * p, e, radius=r)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("folder")
    ap.add_argument("--cases", default="*", help="a glob of case names (default: every case)")
    ap.add_argument("--offsets", default="0", help="comma-separated shares of the radius (default 0: the exact curve)")
    a = ap.parse_args()
    offsets = [float(x) for x in a.offsets.split(",")]
    fired = {k: [0, 0] for k in offsets}
    for path in sorted(glob.glob(os.path.join(a.folder, "clouds", a.cases + ".ply"))):
        name = os.path.basename(path)[:-4]
        cloud = load_cloud(path)
        curve = load_curve(os.path.join(a.folder, "truth", f"{name}_reference.ply"))
        for k in offsets:
            ev = evaluate(cloud, curve=moved(curve, k), workers=1)
            surface = ev.source.ctx.results["curve defects"].surface
            msg = [w.message for w in ev.warnings if w.code == "along_surface"]
            fired[k][0] += bool(msg)
            fired[k][1] += 1
            print(f"{name} offset {k:g}: {'FIRED' if msg else 'quiet'}, slab half {surface.slab_radii:.2f} local radii"
                  f"{', not judged' if 'along_surface' in ev.not_computed else ''} {msg[0] if msg else ''}", flush=True)
    for k, (n, total) in fired.items():
        print(f"offset {k:g}: along_surface on {n} of {total}")


if __name__ == "__main__":
    main()
