"""Calibration and timing of the curve diagnostics (spurious branches, cycles, outside;
docs/diagnostics.md). Every case: a generated shape with a known curve skeleton (skelcore/shapes.py),
normalized (docs/metrics.md 0), its curve sampled (docs/metrics.md 3) and the samples' boundedness computed (docs/metrics.md 2), then
:func:`skelcore.diagnostics.find_curve_defects`.

    .venv/bin/python benchmarks/bench_diagnostics.py false-alarms [--sizes 1000 4096 16384 100000]
    .venv/bin/python benchmarks/bench_diagnostics.py defects [--size 4096]
    .venv/bin/python benchmarks/bench_diagnostics.py hammer
    .venv/bin/python benchmarks/bench_diagnostics.py scans
    .venv/bin/python benchmarks/bench_diagnostics.py speed [--sizes 100000 1000000]

``false-alarms``: the true skeleton of every shape, clean and with 1, 3, 5 % noise (of the local
radius), at each size, several seeds: the share of runs with any defect warning, per shape, noise and
size. ``defects``: controlled defects at graded sizes; the share of runs flagged with the right code
(and, for spurs, whether every inserted spur is among the flagged branches).
"""

from __future__ import annotations

import argparse
import os
import platform
import sys
import time
from collections import defaultdict
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

ROOT = Path(__file__).resolve().parents[1]
SCANS = ROOT / "resources" / "scans"
sys.path.insert(0, str(ROOT))

from skelcore import Params, shapes  # noqa: E402
from skelcore.benchmark import skeleton_defects as gen  # noqa: E402
from skelcore.curve import CurveSkeleton  # noqa: E402
from skelcore.metrics.curve_sampling import sample_curve  # noqa: E402
from skelcore.diagnostics import find_curve_defects  # noqa: E402
from skelcore.geometry import Normalization  # noqa: E402
from skelcore.metrics.boundedness import boundedness  # noqa: E402

SHAPES = {
    "cylinder": shapes.cylinder,
    "Y": shapes.y_shape,
    "T": shapes.t_shape,
    "torus": shapes.torus,
    "genus2": shapes.genus2,
    "tree3": shapes.tree3,
}
CODES = ("spurious_branches", "spurious_cycles", "missing_cycles", "outside")


def diagnose(cloud: np.ndarray, verts: np.ndarray, edges: np.ndarray, params: Params = Params()):
    """Normalize, sample, score the samples' boundedness, run the diagnostics: (result, seconds)."""
    norm = Normalization.from_cloud(cloud, params.normalize_by, params.normalized_size)
    c = norm.apply(cloud)
    curve = CurveSkeleton.from_raw(norm.apply(verts), edges)
    samples = sample_curve(curve, params.curve_samples, collinear_cos=params.collinear_cos)
    beta = boundedness(c, samples.points, params=params)
    t = time.perf_counter()
    d = find_curve_defects(c, curve, samples=samples, sample_boundedness=beta, params=params)
    return d, time.perf_counter() - t


# ---- controlled defects -------------------------------------------------------------------------

def _radius_at(shape: shapes.Shape, pts: np.ndarray) -> np.ndarray:
    d, _ = cKDTree(shape.cloud).query(pts)
    return d


def _inner_vertices(shape: shapes.Shape, away: float = 1.5) -> np.ndarray:
    """Degree-2 vertices at least ``away`` local radii from every node (end or junction)."""
    v = shape.curve_vertices
    return gen.inner_vertices(v, shape.curve_edges, _radius_at(shape, v), away)


# the generators live in skelcore/benchmark/defects.py (shared with `skelcore bench validity`);
# here the local radius is the distance to the cloud

def add_spurs(shape: shapes.Shape, k: int, length: float, rng: np.random.Generator):
    """``k`` spurs of ``length`` local radii from distinct inner vertices, sideways; returns
    (vertices, edges, ids of the new tip vertices)."""
    v = shape.curve_vertices
    return gen.add_spurs(v, shape.curve_edges, _radius_at(shape, v), k, length, rng)


def add_loop(shape: shapes.Shape, span: float, rng: np.random.Generator):
    """A chord closing a loop inside the shape, ``span`` local radii along the curve."""
    v = shape.curve_vertices
    return gen.add_chord(v, shape.curve_edges, _radius_at(shape, v), span, rng)


def cut_open(shape: shapes.Shape, n_edges: int, which: int = 0):
    """Remove ``n_edges`` consecutive edges of the curve, from edge ``which``."""
    e = shape.curve_edges
    keep = np.ones(len(e), bool)
    keep[which:which + n_edges] = False
    return shape.curve_vertices.copy(), e[keep]


def shortcut(shape: shapes.Shape, name: str):
    """An edge through the air between two far vertices (the pair per shape)."""
    v, e = shape.curve_vertices, shape.curve_edges
    deg = np.bincount(e.ravel(), minlength=len(v))
    if name == "torus":
        a, b = 0, len(v) // 2
    elif name == "genus2":
        # across the right loop's hole: its two vertices farthest apart in y
        right = np.flatnonzero(v[:, 0] > 0.5 * v[:, 0].max())
        a, b = int(right[np.argmax(v[right, 1])]), int(right[np.argmin(v[right, 1])])
    else:
        ends = np.flatnonzero(deg == 1)
        d = np.linalg.norm(v[ends][:, None] - v[ends][None], axis=2)
        i, j = np.unravel_index(np.argmax(d), d.shape)
        a, b = int(ends[i]), int(ends[j])
        if name == "T":  # the stem's tip to a bar end
            a = int(np.argmin(v[:, 2]))
            b = int(np.argmin(v[:, 0]))
    return gen.join(v, e, a, b, float(_radius_at(shape, v[a:a + 1])[0]))


def out_branch(shape: shapes.Shape, out_radii: float, rng: np.random.Generator):
    """A terminal branch from an inner vertex straight out of the shape, ``out_radii`` local radii
    beyond its surface."""
    v = shape.curve_vertices
    return gen.out_branch(v, shape.curve_edges, _radius_at(shape, v), out_radii, rng)


# ---- runs ---------------------------------------------------------------------------------------

def codes_of(d) -> set[str]:
    return {w.code for w in d.warnings()}


def false_alarms(sizes: list[int], seeds: int) -> None:
    print("| shape | N | noise | runs | false alarms | codes | diag s (mean) |\n|---|---|---|---|---|---|---|")
    totals = defaultdict(lambda: [0, 0])
    for name, make in SHAPES.items():
        for n in sizes:
            for noise in (0.0, 0.01, 0.03, 0.05):
                hits, runs, seen, secs = 0, 0, defaultdict(int), []
                for seed in range(seeds if n <= 16384 else max(1, seeds // 2)):
                    s = make(n=n, seed=seed)
                    if noise:
                        s = shapes.with_noise(s, noise, seed=seed)
                    d, sec = diagnose(s.cloud, s.curve_vertices, s.curve_edges)
                    got = codes_of(d)
                    runs += 1
                    hits += bool(got)
                    secs.append(sec)
                    for c in got:
                        seen[c] += 1
                totals[name][0] += hits
                totals[name][1] += runs
                print(f"| {name} | {n} | {noise:.0%} | {runs} | {hits} | {dict(seen) or '-'} | {np.mean(secs):.2f} |",
                      flush=True)
    print("\n| shape | false alarms / runs |\n|---|---|")
    for name, (h, r) in totals.items():
        print(f"| {name} | {h} / {r} |")


def defects(size: int, seeds: int, noises: list[float]) -> None:
    rows = []

    def record(defect: str, size_label: str, name: str, expect: str, got: set[str], located: bool | None = None):
        rows.append((defect, size_label, name, expect in got, located, tuple(sorted(got - {expect}))))

    for noise in noises:
        for seed in range(seeds):
            rng = np.random.default_rng(1000 + seed)
            made = {}
            for name, make in SHAPES.items():
                s = make(n=size, seed=seed)
                made[name] = shapes.with_noise(s, noise, seed=seed) if noise else s
            for name, s in made.items():
                # spurs
                for k in (1, 3, 10):
                    for length in (0.5, 1.0, 2.0, 3.0):
                        v, e, tips = add_spurs(s, k, length, rng)
                        d, _ = diagnose(s.cloud, v, e)
                        vb = d.branches.vertex_branch
                        flagged = set(d.spurs.spurious.tolist())
                        located = all(vb[t] in flagged for t in tips)
                        record("spurs", f"{k} x {length} r", name, "spurious_branches", codes_of(d), located)
                # a loop inside
                if name != "genus2":
                    for span in (1.0, 2.0, 4.0):
                        v, e = add_loop(s, span, rng)
                        d, _ = diagnose(s.cloud, v, e)
                        record("loop inside", f"span {span} r", name, "spurious_cycles", codes_of(d))
                # cut open
                if name in ("torus", "genus2"):
                    for ne in (1, 3, 8):
                        v, e = cut_open(s, ne, which=5)
                        d, _ = diagnose(s.cloud, v, e)
                        record("cut open", f"{ne} edges", name, "missing_cycles", codes_of(d))
                # shortcut through the air
                if name != "cylinder":
                    v, e = shortcut(s, name)
                    d, _ = diagnose(s.cloud, v, e)
                    record("shortcut", "-", name, "outside", codes_of(d))
                # a branch out of the shape
                for out in (0.5, 1.0, 3.0, 10.0):
                    v, e = out_branch(s, out, rng)
                    d, _ = diagnose(s.cloud, v, e)
                    record("branch outside", f"{out:g} r out", name, "outside", codes_of(d))
            print(f"# noise {noise:.0%} seed {seed} done ({len(rows)} runs)", flush=True)
    # per defect and size: detection rate over shapes, seeds and noises
    agg = defaultdict(lambda: [0, 0, 0, 0, defaultdict(int)])
    for defect, size_label, name, hit, located, extra in rows:
        a = agg[(defect, size_label)]
        a[0] += hit
        a[1] += 1
        if located is not None:
            a[2] += bool(located)
            a[3] += 1
        for c in extra:
            a[4][c] += 1
    print("\n| defect | size | detected | located | other codes |\n|---|---|---|---|---|")
    for (defect, size_label), (h, n, loc, nloc, extra) in agg.items():
        loc_s = f"{loc}/{nloc}" if nloc else "-"
        print(f"| {defect} | {size_label} | {h}/{n} | {loc_s} | {dict(extra) or '-'} |")
    per_shape = defaultdict(lambda: [0, 0])
    for defect, _, name, hit, _, _ in rows:
        per_shape[(defect, name)][0] += hit
        per_shape[(defect, name)][1] += 1
    print("\n| defect | shape | detected |\n|---|---|---|")
    for (defect, name), (h, n) in per_shape.items():
        print(f"| {defect} | {name} | {h}/{n} |")


def tangle(skeletal: np.ndarray, n: int = 400, k: int = 4, seed: int = 0) -> tuple[np.ndarray, np.ndarray]:
    """A PyGEL-like tangle: ``n`` of the contracted points, each joined to its ``k`` nearest others
    (a graph with hundreds of short cycles inside the shape)."""
    pts = np.unique(skeletal, axis=0)
    pts = pts[np.random.default_rng(seed).choice(len(pts), min(n, len(pts)), replace=False)]
    _, nb = cKDTree(pts).query(pts, k=k + 1)
    e = np.sort(np.column_stack([np.repeat(np.arange(len(pts)), k), nb[:, 1:].ravel()]), axis=1)
    return pts, np.unique(e, axis=0)


def hammer() -> None:
    """Our skeletonizers' hammer skeletons as they are, then cao's with controlled defects."""
    import skelcore

    path = SCANS / "hammer_4096.ply"
    cloud = skelcore.load_cloud(str(path))
    rng = np.random.default_rng(22)
    for method in ("cao", "skelscope"):
        skel, curve = skelcore.skeletonize(cloud, method=method)
        t = time.perf_counter()
        skelcore.evaluate(cloud, skeletal=skel, curve=curve)
        t_ev = time.perf_counter() - t
        cases = {"as made": (curve.vertices, curve.edges)}
        if method == "cao":
            sh = shapes.Shape(cloud, skel, curve.vertices, curve.edges)
            v, e, _ = add_spurs(sh, 10, 1.0, rng)
            cases["ten spurs of 1 r"] = (v, e)
            cases["shortcut handle end - head end"] = shortcut(sh, "hammer")
            cases["chord closing a loop in the handle"] = add_loop(sh, 3.0, rng)
            diag = float(np.linalg.norm(np.ptp(cloud, axis=0)))
            r0 = float(np.median(_radius_at(sh, curve.vertices)))
            cases["branch 30 % of the diagonal out"] = out_branch(sh, 0.3 * diag / r0, rng)
            cases["tangle (kNN graph of 400 contracted points)"] = tangle(skel)
        for label, (v, e) in cases.items():
            d, t_d = diagnose(cloud, v, e)
            b = d.branches
            print(f"{method}, {label}: {len(v)} vertices, {len(b)} branches, {b.cycle_rank} cycles; "
                  f"evaluation {t_ev:.2f} s, diagnostics {t_d:.2f} s")
            for w in d.warnings():
                print(f"  {w.code}: {w.message}")
            if not d.warnings():
                print("  no defect warning")


def scans() -> None:
    """The real scans (resources/scans) with our skeletonizers' curves: what is flagged, and where."""
    import skelcore

    for name in ("hammer_4096.ply", "horse_1987_mesh.ply", "apple_tree_22367.ply", "cave_27375.ply"):
        path = SCANS / name
        cloud = skelcore.load_cloud(str(path))
        for method in ("cao", "skelscope"):
            t = time.perf_counter()
            try:
                skel, curve = skelcore.skeletonize(cloud, method=method)
            except Exception as exc:  # a failed skeletonization is reported, not fatal
                print(f"{name} {method}: skeletonize failed: {exc}")
                continue
            t_s = time.perf_counter() - t
            t = time.perf_counter()
            skelcore.evaluate(cloud, skeletal=skel, curve=curve)
            t_e = time.perf_counter() - t
            d, t_d = diagnose(cloud, curve.vertices, curve.edges)
            b = d.branches
            print(f"{name} {method}: {curve.n_vertices} vertices, {len(b)} branches, {b.cycle_rank} cycles, "
                  f"{d.cycles.shape_tunnels} tunnels; skeletonize {t_s:.1f} s, evaluation {t_e:.2f} s, "
                  f"diagnostics {t_d:.2f} s", flush=True)
            for w in d.warnings():
                print(f"  {w.code}: {w.message}")
            for i, f in enumerate(b.flags):
                if f:
                    p = curve.vertices[b.paths[i]]
                    print(f"    branch {i} ({b.kind[i]}, {b.length[i]:.3g} long, r {b.radius_median[i]:.3g}): "
                          f"{', '.join(f)}; from {np.round(p[0], 3)} to {np.round(p[-1], 3)}")


def speed(sizes: list[int]) -> None:
    import skelcore

    print(f"{platform.processor() or platform.machine()}, {os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    print("| N | evaluation s | diagnostics s | share | branches | interior | spurs | cycles | outside |\n"
          "|---|---|---|---|---|---|---|---|---|")
    for n in sizes:
        s = shapes.torus(n=n, n_curve=64)
        skel = s.skeletal + np.random.default_rng(0).normal(scale=0.003, size=s.skeletal.shape)
        t = time.perf_counter()
        ev = skelcore.evaluate(s.cloud, skeletal=skel, curve=(s.curve_vertices, s.curve_edges))
        t_ev = time.perf_counter() - t
        norm = ev.normalization
        curve = ev.curve.curve.transformed(norm.apply)
        samples = sample_curve(curve, ev.params.curve_samples)
        t = time.perf_counter()
        d = find_curve_defects(norm.apply(ev.cloud), curve, samples=samples,
                               sample_boundedness=ev.curve.sample_boundedness,
                               skeletal=norm.apply(ev.skeletal.points), skeletal_boundedness=ev.skeletal.boundedness)
        t_d = time.perf_counter() - t
        tm = d.timings
        print(f"| {n} | {t_ev:.2f} | {t_d:.2f} | {t_d / t_ev:.0%} | {tm['branches']:.2f} | {tm['interior']:.2f} | "
              f"{tm['spurs']:.2f} | {tm['cycles']:.2f} | {tm['outside']:.2f} | codes {sorted(codes_of(d)) or '-'}",
              flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("what", choices=["false-alarms", "defects", "hammer", "scans", "speed"])
    ap.add_argument("--sizes", type=int, nargs="+")
    ap.add_argument("--size", type=int, default=4096)
    ap.add_argument("--seeds", type=int, default=3)
    ap.add_argument("--noises", type=float, nargs="+", default=[0.0, 0.03])
    args = ap.parse_args()
    print(f"load {os.getloadavg()[0]:.1f}")
    if args.what == "false-alarms":
        false_alarms(args.sizes or [1000, 4096, 16384, 100000], args.seeds)
    elif args.what == "defects":
        defects(args.size, args.seeds, args.noises)
    elif args.what == "hammer":
        hammer()
    elif args.what == "scans":
        scans()
    else:
        speed(args.sizes or [100000, 1000000])


if __name__ == "__main__":
    main()
