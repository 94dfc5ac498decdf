"""Validation of the real-scan additions (docs/metrics.md 6.6): openings, ``open_surface``,
viewpoint-aware scores, ``--cap-openings``, stray points.  Prints markdown tables.

- closed: generated closed shapes (cylinder, torus, Y, tree) with 0-5 % noise (of the tube radius) and
  1k-100k points: openings found, and whether ``open_surface`` fires on the true skeleton (up to 10k);
- partial: the same shapes scanned from 1-3 viewpoints (hidden point removal, sensors 10 extents away):
  openings, ``open_surface``, and the true skeleton's scores without and with the viewpoints against
  the complete shape's;
- issue: partial scans of known shapes (cylinder cut at y > -0.1 and y > 0, the hammer less 10 / 25 % of its
  points on its -x side, a tube with open ends, capped), with viewpoints / caps;
- outliers: one point at 10 x the hammer's extent, 40 points in a box twice the hammer's (in the cloud and
  the skeletal set), clean noisy shapes; with and without ``remove_outliers``;
- timing: viewpoint-aware boundedness against the paper's on the hammer and on tori.

    .venv/bin/python benchmarks/bench_scans.py [--sections closed partial issue outliers timing] [--quick]
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

from skelcore import Params, evaluate, shapes, skeletonize  # noqa: E402
from skelcore.scan.openings import find_openings  # noqa: E402
from skelcore.scan.synthetic import seen_from  # noqa: E402

SCANS = ROOT / "resources" / "scans"
RADIUS = {"cylinder": 0.5, "torus": 0.3, "y": 0.25, "tree": 0.25}
VIEWS = {
    "1 level": [[0, 1, 0]],
    "1 above": [[0, 1, 0.3]],
    "1 top": [[0.1, 0.2, 1]],
    "2": [[0, 1, 0.3], [1, 0, -0.3]],
    "3": [[0, 1, 0.3], [1, -0.5, -0.3], [-1, -0.5, 0.5]],
}


def make(name: str, n: int, seed: int = 0) -> shapes.Shape:
    return {"cylinder": lambda: shapes.cylinder(n, seed=seed), "torus": lambda: shapes.torus(n, seed=seed),
            "y": lambda: shapes.y_shape(n, seed=seed), "tree": lambda: shapes.branching_tree(n, seed=seed)}[name]()


def noisy(cloud: np.ndarray, level: float, radius: float, seed: int = 1) -> np.ndarray:
    return cloud + np.random.default_rng(seed).normal(scale=level * radius, size=cloud.shape)


def scores(ev) -> dict:
    s = ev.summary()
    return {f"{m[0]}_{c[0]}": s[m][c] for m in ("boundedness", "centeredness") for c in ("skeletal", "curve")}


def codes(ev) -> str:
    return ", ".join(w.code for w in ev.warnings) or "-"


def viewpoints(cloud: np.ndarray, views) -> np.ndarray:
    centre = (cloud.min(axis=0) + cloud.max(axis=0)) / 2
    v = np.asarray(views, dtype=float)
    return centre + 10 * np.ptp(cloud, axis=0).max() * v / np.linalg.norm(v, axis=1, keepdims=True)


def closed(quick: bool) -> None:
    print("\n### Closed shapes: openings found, open_surface on the true skeleton\n")
    print("| shape | points | noise | openings | open_surface | outliers | curve boundedness |")
    print("|---|---|---|---|---|---|---|")
    sizes = (1000, 10000) if quick else (1000, 10000, 100000)
    for name in RADIUS:
        for n in sizes:
            for level in (0.0, 0.01, 0.03, 0.05):
                s = make(name, n)
                cloud = noisy(s.cloud, level, RADIUS[name]) if level else s.cloud
                n_open = len(find_openings(cloud))
                if n <= 10000:
                    ev = evaluate(cloud, s.skeletal, (s.curve_vertices, s.curve_edges))
                    fired = "yes" if any(w.code == "open_surface" for w in ev.warnings) else "no"
                    outl = "yes" if any(w.code == "outliers" for w in ev.warnings) else "no"
                    b = f"{ev.summary()['boundedness']['curve']:.3f}"
                else:  # the warning cannot fire without an opening
                    ev = evaluate(cloud, None, (s.curve_vertices, s.curve_edges))
                    fired = "yes" if any(w.code == "open_surface" for w in ev.warnings) else "no"
                    outl = "yes" if any(w.code == "outliers" for w in ev.warnings) else "no"
                    b = f"{ev.summary()['boundedness']['curve']:.3f}"
                print(f"| {name} | {n} | {level:.0%} | {n_open} | {fired} | {outl} | {b} |", flush=True)


def partial(quick: bool) -> None:
    print("\n### One-sided scans (hidden point removal), true skeleton: complete / partial / partial with viewpoints\n")
    print("| shape | views | kept | openings | warnings (partial) | curve boundedness | curve centeredness "
          "| skeletal boundedness | skeletal centeredness | seconds (viewpoints) |")
    print("|---|---|---|---|---|---|---|---|---|---|")
    n = 4096 if quick else 8192
    for name in RADIUS:
        s = make(name, n)
        curve = (s.curve_vertices, s.curve_edges)
        full = scores(evaluate(s.cloud, s.skeletal, curve))
        for label, views in VIEWS.items():
            v = viewpoints(s.cloud, views)
            m = seen_from(s.cloud, v)
            part = evaluate(s.cloud[m], s.skeletal[m], curve)
            t0 = time.perf_counter()
            seen = evaluate(s.cloud[m], s.skeletal[m], curve, viewpoints=v)
            dt = time.perf_counter() - t0
            p, q = scores(part), scores(seen)
            n_open = len(find_openings(s.cloud[m]))
            cells = " | ".join(f"{full[k]:.3f} / {p[k]:.3f} / **{q[k]:.3f}**" for k in ("b_c", "c_c", "b_s", "c_s"))
            print(f"| {name} | {label} | {m.mean():.2f} | {n_open} | {codes(part)} | {cells} | {dt:.1f} |", flush=True)


def issue(quick: bool) -> None:
    print("\n### Partial scans of known shapes, with viewpoints and caps\n")
    print("| cloud | skeleton | B curve | C curve | B skeletal | C skeletal | warnings |")
    print("|---|---|---|---|---|---|---|")

    def row(label, ev, skel="true"):
        s = scores(ev)
        f = lambda k: "-" if s[k] is None else f"{s[k]:.3f}"  # noqa: E731
        print(f"| {label} | {skel} | {f('b_c')} | {f('c_c')} | {f('b_s')} | {f('c_s')} | {codes(ev)} |", flush=True)

    c = shapes.cylinder(8192)
    curve = (c.curve_vertices, c.curve_edges)
    far_y = [[0.0, 40.0, 2.0]]
    row("cylinder, complete", evaluate(c.cloud, c.skeletal, curve))
    for cut, label in ((-0.1, "y > -0.1 (3/4 view)"), (0.0, "y > 0 (front half)")):
        k = c.cloud[:, 1] > cut
        row(f"cylinder, {label}", evaluate(c.cloud[k], c.skeletal[k], curve))
        row(f"cylinder, {label}, viewpoint (0, 40, 2)", evaluate(c.cloud[k], c.skeletal[k], curve, viewpoints=far_y))
        row(f"cylinder, {label}, --cap-openings", evaluate(c.cloud[k], c.skeletal[k], curve, cap_openings=True))
    t = shapes.cylinder(8192, length=8.0, capped=False)
    row("tube with open ends (length 16 r)", evaluate(t.cloud, t.skeletal, (t.curve_vertices, t.curve_edges)))
    row("the same, --cap-openings", evaluate(t.cloud, t.skeletal, (t.curve_vertices, t.curve_edges), cap_openings=True))
    from skelcore.io import load_cloud

    h = load_cloud(SCANS / "hammer_4096.ply")
    sk, cv = skeletonize(h, method="cao")
    centre, extent = (h.min(axis=0) + h.max(axis=0)) / 2, np.ptp(h, axis=0)
    vp = [[centre[0] + 10 * extent.max(), centre[1], centre[2]]]
    row("hammer, complete", evaluate(h, sk, cv), "cao")
    row("hammer, complete, viewpoint +x", evaluate(h, sk, cv, viewpoints=vp), "cao")
    for frac in (0.10, 0.25):
        k = h[:, 0] > np.quantile(h[:, 0], frac)
        row(f"hammer less {frac:.0%} (-x side)", evaluate(h[k], sk[k], cv), "cao")
        row(f"hammer less {frac:.0%}, viewpoint +x", evaluate(h[k], sk[k], cv, viewpoints=vp), "cao")


def outliers(quick: bool) -> None:
    print("\n### Stray points\n")
    from skelcore.io import load_cloud

    h = load_cloud(SCANS / "hammer_4096.ply")
    sk, cv = skeletonize(h, method="cao")
    centre, extent = (h.min(axis=0) + h.max(axis=0)) / 2, np.ptp(h, axis=0)
    far = centre + 10 * extent * np.array([1.0, 0.3, 0.2])
    print("| hammer (cao) | d_B | d_Wp | B skel / curve | C skel / curve | warnings |")
    print("|---|---|---|---|---|---|")

    def row(label, ev):
        s, t = ev.summary(), ev.summary()["topology"]
        print(f"| {label} | {t['bottleneck']:.4f} | {t['wasserstein']:.5f} | {s['boundedness']['skeletal']:.3f} / "
              f"{s['boundedness']['curve']:.3f} | {s['centeredness']['skeletal']:.3f} / {s['centeredness']['curve']:.3f}"
              f" | {codes(ev)} |", flush=True)

    row("clean", evaluate(h, sk, cv))
    for label, extra in (("+1 point at 10 x the extent", far[None, :]),) + tuple(
            (f"+40 points in a box twice the extent (seed {seed})",
             centre + np.random.default_rng(seed).uniform(-1, 1, (40, 3)) * extent) for seed in (0, 1, 2)):
        c2, s2 = np.vstack([h, extra]), np.vstack([sk, extra])
        row(label, evaluate(c2, s2, cv))
        row(label + ", remove_outliers", evaluate(c2, s2, cv, remove_outliers=True))
        row(label + ", bounding-box extents (trust_extent_quantile = 0)",
            evaluate(c2, s2, cv, params=Params(trust_extent_quantile=0.0)))
    print("\n| clean shape | points | noise | outliers found |")
    print("|---|---|---|---|")
    from skelcore.scan.outliers import find_outliers

    for name in RADIUS:
        for n in (1000, 10000) if quick else (1000, 10000, 100000):
            for level in (0.0, 0.01, 0.03, 0.05):
                s = make(name, n)
                cloud = noisy(s.cloud, level, RADIUS[name]) if level else s.cloud
                print(f"| {name} | {n} | {level:.0%} | {find_outliers(cloud).count} |", flush=True)


def timing(quick: bool) -> None:
    from skelcore.geometry import Normalization
    from skelcore.metrics.boundedness import boundedness
    from skelcore.scan.viewpoint import seen_boundedness

    print(f"\n### Viewpoint-aware boundedness, seconds (CPU of the process / wall), load {os.getloadavg()[0]:.1f}\n")
    print("| case | queries | paper's rays | viewpoint-aware (one sensor) |")
    print("|---|---|---|---|")
    cases = []
    from skelcore.io import load_cloud

    h = load_cloud(SCANS / "hammer_4096.ply")
    cases.append(("hammer, cao skeletal set", h, skeletonize(h, method="cao")[0]))
    for n in (4096, 16384) if quick else (4096, 16384, 65536):
        t = shapes.torus(n)
        cases.append((f"torus {n}, skeletal set", t.cloud, t.skeletal))
    for label, cloud, queries in cases:
        norm = Normalization.from_cloud(cloud)
        c, q = norm.apply(cloud), norm.apply(queries)
        v = norm.apply(viewpoints(cloud, [[0, 1, 0.3]]))
        out = []
        for fn in (lambda: boundedness(c, q, params=Params()), lambda: seen_boundedness(c, q, v)):
            cpu, wall = time.process_time(), time.perf_counter()
            fn()
            out.append(f"{time.process_time() - cpu:.1f} / {time.perf_counter() - wall:.1f}")
        print(f"| {label} | {len(np.unique(q, axis=0))} | {out[0]} | {out[1]} |", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--sections", nargs="+", default=["closed", "partial", "issue", "outliers", "timing"])
    ap.add_argument("--quick", action="store_true", help="fewer sizes (no 100k)")
    args = ap.parse_args()
    for name in args.sections:
        globals()[name](args.quick)


if __name__ == "__main__":
    main()
