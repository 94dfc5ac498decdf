"""The counts of docs/diagnostics.md "Along the surface": each case of a benchmark folder (``skelcore
bench make DIR``, ``--suite real``) evaluated with its exact reference curve, and with that curve's
every vertex moved ``--offsets`` of its radius towards the wall (a fixed direction made perpendicular
to the curve's tangent at the vertex); one line per run (``along_surface`` fired or not, the slab's
half in local radii, "not judged" when it is too thick), then the fired counts per offset.
``--local-slab K,K``: also Eq. 11's c of every bounded sample from a slab K of its local radii thick
on each side (:mod:`skelcore.metrics.local_slabs`), and per K and offset how well it tells the moved
curves' samples from the exact one's (AUC: the chance that a moved sample's c is below an exact one's).

    python scripts/surface_counts.py DIR [--cases GLOB] [--offsets 0,0.2,0.6] [--local-slab 1,2]
"""

from __future__ import annotations

import argparse
import glob
import os

import numpy as np

from skelcore import evaluate
from skelcore.benchmark.validity_stats import auc
from skelcore.benchmark.skeleton_defects import vertex_tangents
from skelcore.curve import CurveSkeleton
from skelcore.geometry import kd_tree
from skelcore.io.loaders import load_cloud, load_curve
from skelcore.metrics.local_slabs import local_slab_centeredness

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
    ap.add_argument("--local-slab", default="", help="comma-separated slab halves in local radii (default: none)")
    a = ap.parse_args()
    offsets = [float(x) for x in a.offsets.split(",")]
    slabs = [float(x) for x in a.local_slab.split(",") if x]
    fired = {k: [0, 0] for k in offsets}
    local: dict[tuple[float, float], list[np.ndarray]] = {(s, k): [] for s in slabs for k in offsets}
    for path in sorted(glob.glob(os.path.join(a.folder, "clouds", a.cases + ".ply"))):
        name = os.path.basename(path)[:-4]
        cloud = load_cloud(path)
        curve = load_curve(os.path.join(a.folder, "truth", f"{name}_reference.ply"))
        for k in offsets:
            ev = evaluate(cloud, curve=moved(curve, k), workers=1)
            surface = ev.source.ctx.results["curve defects"].surface
            msg = [w.message for w in ev.warnings if w.code == "along_surface"]
            for s in slabs:
                local[s, k].append(_local_c(ev, s))
            fired[k][0] += bool(msg)
            fired[k][1] += 1
            print(f"{name} offset {k:g}: {'FIRED' if msg else 'quiet'}, slab half {surface.slab_radii:.2f} local radii"
                  f"{', not judged' if 'along_surface' in ev.not_computed else ''} {msg[0] if msg else ''}", flush=True)
    for k, (n, total) in fired.items():
        print(f"offset {k:g}: along_surface on {n} of {total}")
    for s in slabs:
        exact = np.concatenate(local[s, offsets[0]])
        for k in offsets[1:]:
            got = np.concatenate(local[s, k])
            print(f"local slab {s:g} radii: c median {np.median(exact):.2f} at offset {offsets[0]:g}, {np.median(got):.2f} "
                  f"at {k:g}; AUC {auc(-got, -exact):.2f} ({len(got)} and {len(exact)} samples)")


def _local_c(ev, slab: float) -> np.ndarray:
    """The local-slab c of the evaluation's bounded curve samples that have one (above 0 or 0)."""
    ctx = ev.source.ctx
    s = ctx.samples
    r = kd_tree(ctx.cloud_n).query(s.points)[0]
    c = local_slab_centeredness(ctx.cloud_n, s.points, s.directions, slab * r, params=ev.params)
    bounded = np.asarray(ctx.results["curve boundedness"], float) > ev.params.beta_star
    return c[bounded & np.isfinite(c)]


if __name__ == "__main__":
    main()
