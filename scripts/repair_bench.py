"""Measure skelcore.repair on a benchmark suite (docs/repair.md "Measured"): for each case, the curves
of the built-in skeletonizers and, on the clean cases, the reference with one controlled defect
(skelcore.benchmark.skeleton_defects at its middle level); GT F1 and the defect counts before and
after repair, the time per repair. Usage: python scripts/repair_bench.py SUITE_DIR|samples OUT.json"""

from __future__ import annotations

import json
import sys
import time
import zlib
from pathlib import Path

import numpy as np

import skelcore
from skelcore import CurveSkeleton
from skelcore.benchmark.skeleton_defects import DEFECTS, apply_defect
from skelcore.benchmark.tubes import signed_distance
from skelcore.benchmark.validity import _shape
from skelcore.io import load_cloud, load_curve
from skelcore.metrics.ground_truth import compare_with_ground_truth

METHODS = ("cao", "skelscope")
DEFECT_NAMES = ("spurs", "shortcut", "chord_cycle", "broken_cycle", "missing_branch", "noise", "offset")
WARN = ("spurious_branches", "spurious_cycles", "missing_cycles", "outside", "incomplete")


def _f1(curve: CurveSkeleton, ref: CurveSkeleton) -> float:
    return float(compare_with_ground_truth(curve, ref, ref.radius).f1)


def _job(name: str, what: str, cloud: np.ndarray, curve: CurveSkeleton, ref: CurveSkeleton) -> dict:
    row = {"case": name, "job": what, "f1_before": _f1(curve, ref)}
    try:
        r = skelcore.repair(cloud, curve)
    except skelcore.SkelInputError as exc:
        return {**row, "refused": str(exc)}
    row.update(f1_after=_f1(r.curve, ref), seconds=round(r.seconds, 2), kept=r.accepted, rejected=r.rejected,
               stopped=r.stopped, defects_before=sum(r.tally_before.values()),
               defects_after=sum(r.tally_after.values()),
               warnings_before=sorted({w.code for w in r.before.warnings} & set(WARN)),
               warnings_after=sorted({w.code for w in r.after.warnings} & set(WARN)))
    return row


def samples(out: str) -> None:
    """The bundled samples (resources/samples): each skeletonizer's curve and the bundled LBC curve."""
    root = Path(__file__).resolve().parents[1] / "resources" / "samples"
    rows = []
    for name in ("cylinder", "torus", "yshape"):
        cloud = load_cloud(root / f"{name}_cloud.ply")
        ref = load_curve(root / f"{name}_curve.ply")
        if ref.radius is None:
            from skelcore.metrics.ground_truth import radius_from_cloud
            ref = CurveSkeleton(vertices=ref.vertices, edges=ref.edges, radius=radius_from_cloud(ref.vertices, cloud, 8))
        curves = {m: skelcore.skeletonize(cloud, method=m)[1] for m in METHODS}
        curves["lbc (bundled)"] = load_curve(root / f"{name}_lbc_curve.ply")
        for what, curve in curves.items():
            rows.append(_job(name, what, cloud, curve, ref))
            print(" ", rows[-1], flush=True)
    Path(out).write_text(json.dumps(rows, indent=1))


def main(suite: str, out: str) -> None:
    if suite == "samples":
        return samples(out)
    root = Path(suite)
    meta = json.loads((root / "suite.json").read_text())
    rows = []
    for case in sorted((root / "cases").glob("*.json")):
        c = json.loads(case.read_text())
        cloud = load_cloud(root / c["files"]["cloud"])
        ref = load_curve(root / c["files"]["reference"])
        for m in METHODS:
            t0 = time.perf_counter()
            _, curve = skelcore.skeletonize(cloud, method=m)
            print(c["name"], m, f"{time.perf_counter() - t0:.1f}s", flush=True)
            rows.append(_job(c["name"], m, cloud, curve, ref))
            print(" ", rows[-1], flush=True)
        if c["effect"] != "clean" or c["shape"] == "plate":
            continue
        shape = _shape(c["shape"], int(meta["seed"]))[0]
        for d in DEFECT_NAMES:
            level = DEFECTS[d].levels[1]
            rng = np.random.default_rng(np.random.SeedSequence([int(meta["seed"]), zlib.crc32(f"{c['name']}/{d}".encode())]))
            made = apply_defect(d, level, ref.vertices, ref.edges, ref.radius, rng,
                                lambda p: signed_distance(shape, p, spacing=0.1))
            if made is None or len(made[1]) == 0:
                continue
            rows.append(_job(c["name"], f"defect {d} {DEFECTS[d].label(level)}", cloud,
                             CurveSkeleton.from_raw(*made), ref))
            print(" ", rows[-1], flush=True)
    Path(out).write_text(json.dumps(rows, indent=1))


if __name__ == "__main__":
    main(*sys.argv[1:3])
