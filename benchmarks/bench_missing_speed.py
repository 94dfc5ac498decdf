"""Speed of the missing-parts diagnostic against a full evaluation (docs/diagnostics.md "Speed").

The torus of bench_engine.py (R = 1, r = 0.3, N points; skeletal set = each point's projection onto
the core circle + 1 % jitter; curve = a 64-gon of the core circle). For each size: the full
evaluation (skeletal set and curve; coverage included up to coverage_max_points), then
``missing_parts`` for the skeletal set and for the curve, given the evaluation's coverage when it has
one (as the evaluation would call it) and alone (its own coverage, subsampled above
missing_max_points). Wall and CPU seconds, the load beside. Also: the verdicts on the full cloud
and on a subsample agree (intact and half-cut torus).

    PYTHONPATH=. .venv/bin/python benchmarks/bench_missing_speed.py [--sizes 100000 1000000] [--no-eval]
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

from skelcore import evaluate, shapes  # noqa: E402
from skelcore.curve import CurveSkeleton  # noqa: E402
from skelcore.diagnostics import missing_parts  # noqa: E402
from skelcore.geometry import Normalization  # noqa: E402
from skelcore.params import Params  # noqa: E402


def timed(fn):
    c, w = time.process_time(), time.perf_counter()
    out = fn()
    return out, time.process_time() - c, time.perf_counter() - w


def torus_case(n: int):
    t = shapes.torus(n, seed=0)
    rng = np.random.default_rng(0)
    skel = t.skeletal + rng.normal(scale=0.01, size=t.skeletal.shape)
    v = np.array([[np.cos(a), np.sin(a), 0.0] for a in np.linspace(0, 2 * np.pi, 64, endpoint=False)])
    curve = CurveSkeleton.from_raw(v, [[i, (i + 1) % 64] for i in range(64)])
    return t.cloud, skel, curve


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[100_000, 1_000_000])
    ap.add_argument("--no-eval", action="store_true", help="skip the full evaluation")
    ap.add_argument("--verdicts", type=int, default=400_000, help="cloud size of the subsample check (0: skip)")
    args = ap.parse_args()
    p = Params()
    print(f"{os.cpu_count()} cores, load {os.getloadavg()[0]:.1f}")
    print("| N | case | CPU s | wall s | note |\n|---|---|---|---|---|")
    for n in args.sizes:
        cloud, skel, curve = torus_case(n)
        norm = Normalization.from_cloud(cloud)
        c, s, cv = norm.apply(cloud), norm.apply(skel), curve.transformed(norm.apply)
        ev = None
        if not args.no_eval:
            ev, cpu, wall = timed(lambda: evaluate(cloud, skel, curve))
            print(f"| {n} | full evaluation (skeletal + curve) | {cpu:.1f} | {wall:.1f} | "
                  f"load {os.getloadavg()[0]:.1f} |")
        for what, sk, cov in (("skeletal", s, ev.coverage_skeletal if ev else None),
                              ("curve", cv, ev.coverage_curve if ev else None)):
            if cov is not None:
                mp, cpu, wall = timed(lambda: missing_parts(c, sk, p, cov=cov))
                print(f"| {n} | missing parts, {what}, the evaluation's coverage | {cpu:.2f} | {wall:.2f} | "
                      f"incomplete {mp.incomplete}, completeness {mp.completeness:.3f} |")
            mp, cpu, wall = timed(lambda: missing_parts(c, sk, p))
            print(f"| {n} | missing parts, {what}, alone | {cpu:.2f} | {wall:.2f} | incomplete {mp.incomplete}, "
                  f"completeness {mp.completeness:.3f}, subsample {mp.subsample} |")
        ang = np.arctan2(skel[:, 1], skel[:, 0])
        cut = s[ang < np.pi / 3]  # two thirds of the ring kept: a third of the cloud unexplained
        mp, cpu, wall = timed(lambda: missing_parts(c, cut, p))
        print(f"| {n} | missing parts, skeletal with a third of the ring cut out, alone | {cpu:.2f} | {wall:.2f} | "
              f"incomplete {mp.incomplete}, completeness {mp.completeness:.3f}, subsample {mp.subsample} |")
        print(f"load {os.getloadavg()[0]:.1f}", file=sys.stderr)
    if args.verdicts:
        n = args.verdicts
        cloud, skel, curve = torus_case(n)
        norm = Normalization.from_cloud(cloud)
        c = norm.apply(cloud)
        ang = np.arctan2(skel[:, 1], skel[:, 0])
        for label, sk in (("intact", skel), ("a third cut out", skel[ang < np.pi / 3 * 4 - np.pi])):
            full = missing_parts(c, norm.apply(sk), p.replace(missing_max_points=n))
            sub = missing_parts(c, norm.apply(sk), p)
            agree = float(np.mean(full.missing == sub.missing))
            print(f"| {n} | verdicts, {label}: all points vs {sub.subsample} | | | "
                  f"incomplete {full.incomplete} / "
                  f"{sub.incomplete}; completeness {full.completeness:.3f} / {sub.completeness:.3f}; regions "
                  f"{[(round(r.share, 3), round(r.depth, 2)) for r in full.counted]} / "
                  f"{[(round(r.share, 3), round(r.depth, 2)) for r in sub.counted]}; per-point flags agree {agree:.4f} |")


if __name__ == "__main__":
    main()
