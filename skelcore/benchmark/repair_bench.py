"""The repair measured on a benchmark folder (docs/repair.md "Measured"): every case's cloud skeletonized
by each tool (the built-in ``cao`` / ``skelscope`` / ``default``, the adapters ``pygel`` / ``kimimaro`` / ``skimage``),
then repaired; on a generated suite's clean tube cases also the reference with one controlled defect
(:mod:`.skeleton_defects` at its middle level). Per job: GT F1 (docs/metrics.md 5.3.1; on a real
suite's case also ``held_f1``, on the reference the cloud can show: the case's facts file) and the defect
warnings and tallies before and after, the seconds of the skeletonization and of the repair (wall
clock, and CPU of the process's threads: ``cpu_skeletonize``, ``cpu_repair``, and the repair's CPU by
phase, ``cpu_phases``: :attr:`~skelcore.skeleton_repair.RepairResult.phases`).
``samples`` instead of a folder: the bundled samples of resources/samples. Behind
``skelcore bench repair``; the table and summary are :mod:`.repair_table`'s.
"""

from __future__ import annotations

import fnmatch
import json
import time
import zlib
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterator, Sequence

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from .neurons import read_outside_radii

__all__ = ["BUILT_IN", "DEFECT_NAMES", "WARNINGS", "RepairCase", "repair_cases", "skeletonize_with", "repair_job",
           "run_repair_bench"]

#: the skeletonizers of skelcore itself ("default": what skelcore skeletonize starts from, cao or the
#: axis curve on thin parts); the adapters' kinds (skelcore.adapters.KINDS) may be named too
BUILT_IN = ("cao", "skelscope", "default")
#: the controlled defects put on a clean tube case's reference
DEFECT_NAMES = ("spurs", "shortcut", "chord_cycle", "broken_cycle", "missing_branch", "noise", "offset")
#: the defect warnings counted before and after
WARNINGS = ("spurious_branches", "spurious_cycles", "missing_cycles", "outside", "incomplete")
SAMPLES_DIR = Path(__file__).resolve().parents[2] / "resources" / "samples"


@dataclass
class RepairCase:
    """One cloud and its reference; ``defects`` says whether reference-with-defect jobs apply."""

    name: str
    cloud: np.ndarray
    reference: CurveSkeleton
    defects: bool = False
    shape: str = ""
    seed: int = 0
    bundled: CurveSkeleton | None = None
    outside_radii: np.ndarray | None = None


def _samples() -> Iterator[RepairCase]:
    from ..io import load_cloud, load_curve
    from ..metrics.ground_truth import radius_from_cloud

    for name in ("cylinder", "torus", "yshape"):
        cloud = load_cloud(SAMPLES_DIR / f"{name}_cloud.ply")
        ref = load_curve(SAMPLES_DIR / f"{name}_curve.ply")
        if ref.radius is None:
            ref = CurveSkeleton(vertices=ref.vertices, edges=ref.edges, radius=radius_from_cloud(ref.vertices, cloud, 8))
        yield RepairCase(name, cloud, ref, bundled=load_curve(SAMPLES_DIR / f"{name}_lbc_curve.ply"))


def repair_cases(folder: str | Path, only: Sequence[str] = ()) -> Iterator[RepairCase]:
    """The cases of a folder of ``skelcore bench make`` (any suite), or the bundled samples for
    ``"samples"``; ``only``: shell patterns of case names to keep (all when empty)."""
    from ..io import load_cloud, load_curve

    if str(folder) == "samples":
        yield from (c for c in _samples() if not only or any(fnmatch.fnmatch(c.name, p) for p in only))
        return
    root = Path(folder)
    if not (root / "suite.json").is_file():
        raise SkelInputError("not a benchmark folder (no suite.json; write one with skelcore bench make)", root)
    meta = json.loads((root / "suite.json").read_text(encoding="utf-8"))
    for path in sorted((root / "cases").glob("*.json")):
        c = json.loads(path.read_text(encoding="utf-8"))
        if only and not any(fnmatch.fnmatch(c["name"], p) for p in only):
            continue
        generated = c.get("curve_skeleton") != "traced"
        ref = load_curve(root / c["files"]["reference"])
        facts = c["files"].get("facts")
        yield RepairCase(c["name"], load_cloud(root / c["files"]["cloud"]), ref,
                         defects=generated and c.get("effect") == "clean" and c.get("shape") != "plate",
                         shape=str(c.get("shape", "")), seed=int(meta.get("seed", 0)),
                         outside_radii=None if not facts else read_outside_radii(root / facts, ref.n_vertices))


def skeletonize_with(tool: str, cloud: np.ndarray, params: dict[str, Any] | None = None
                     ) -> tuple[CurveSkeleton, np.ndarray | None]:
    """The curve (and the pointwise skeletal set when the tool gives one) of ``tool`` on ``cloud``."""
    if tool == "default":
        from ..skeleton.default import default_skeleton

        skeletal, curve, _info, _choice = default_skeleton(cloud)
        return curve, skeletal
    if tool in BUILT_IN:
        from ..skeleton import skeletonize

        skeletal, curve = skeletonize(cloud, method=tool)
        return curve, skeletal
    from ..adapters import run

    res = run(tool, cloud, params or {})
    return res.curve, (res.skeletal if res.correspondence == "auto" else None)


def _f1(curve: CurveSkeleton, case: RepairCase, when: str) -> dict[str, float]:
    """``f1_{when}`` and, when the case's facts are known, ``held_f1_{when}`` (docs/metrics.md 5.3.1)."""
    from ..metrics.ground_truth import compare_with_ground_truth

    held = case.outside_radii is not None
    if curve.n_edges == 0:
        return {f"f1_{when}": 0.0, **({f"held_f1_{when}": 0.0} if held else {})}
    gt = compare_with_ground_truth(curve, case.reference, case.reference.radius, outside_radii=case.outside_radii)
    return {f"f1_{when}": round(float(gt.f1), 4), **({f"held_f1_{when}": round(float(gt.held_f1), 4)} if held else {})}


def _warned(ev: Any) -> list[str]:
    return sorted({w.code for w in ev.warnings} & set(WARNINGS))


def repair_job(case: RepairCase, job: str, curve: CurveSkeleton, seconds_skeletonize: float | None = None
               ) -> dict[str, Any]:
    """One repair of ``curve`` against the case's cloud: GT F1, warnings and tallies before and after."""
    from ..skeleton_repair import repair

    row: dict[str, Any] = {"case": case.name, "job": job, **_f1(curve, case, "before"),
                           "seconds_skeletonize": None if seconds_skeletonize is None else round(seconds_skeletonize, 2)}
    cpu = time.process_time()
    try:  # the curve alone, as skelcore skeletonize repairs it (docs/repair.md "The real suite")
        r = repair(case.cloud, curve)
    except SkelInputError as exc:
        return {**row, "refused": str(exc)}
    row.update(**_f1(r.curve, case, "after"), seconds_repair=round(r.seconds, 2),
               cpu_repair=round(time.process_time() - cpu, 2), kept=r.accepted,
               rejected=r.rejected, stopped=r.stopped, tally_before=dict(r.tally_before),
               tally_after=dict(r.tally_after), warnings_before=_warned(r.before), warnings_after=_warned(r.after),
               cpu_phases=r.phases)
    return row


def _defect_jobs(case: RepairCase) -> Iterator[tuple[str, CurveSkeleton]]:
    from .skeleton_defects import DEFECTS, apply_defect
    from .tubes import signed_distance
    from .validity import _shape

    shape = _shape(case.shape, case.seed)[0]
    ref = case.reference
    for d in DEFECT_NAMES:
        level = DEFECTS[d].levels[1]
        rng = np.random.default_rng(np.random.SeedSequence([case.seed, zlib.crc32(f"{case.name}/{d}".encode())]))
        made = apply_defect(d, level, ref.vertices, ref.edges, ref.radius, rng,
                            lambda p: signed_distance(shape, p, spacing=0.1))
        if made is not None and len(made[1]):
            yield f"defect {d} {DEFECTS[d].label(level)}", CurveSkeleton.from_raw(*made)


def run_repair_bench(folder: str | Path, tools: Sequence[str] = BUILT_IN, *, only: Sequence[str] = (),
                     defects: bool = True, params: dict[str, dict[str, Any]] | None = None,
                     progress: Callable[[dict[str, Any]], None] | None = None) -> list[dict[str, Any]]:
    """Every job's row (:func:`repair_job`), cases in name order, tools in the given order, then the
    defect jobs of the case; a tool that fails on a case gives a row with ``failed`` (one line)."""
    rows = []

    def done(row: dict[str, Any]) -> None:
        rows.append(row)
        if progress is not None:
            progress(row)

    for case in repair_cases(folder, only):
        for tool in tools:
            t0, cpu = time.perf_counter(), time.process_time()
            try:
                curve, _skeletal = skeletonize_with(tool, case.cloud, (params or {}).get(tool))
            except (SkelInputError, ValueError, MemoryError) as exc:
                done({"case": case.name, "job": tool, "failed": " ".join(str(exc).split())[:200]})
                continue
            cpu = time.process_time() - cpu
            done({**repair_job(case, tool, curve, time.perf_counter() - t0), "cpu_skeletonize": round(cpu, 2)})
        if case.bundled is not None:
            done(repair_job(case, "lbc (bundled)", case.bundled))
        if defects and case.defects:
            for job, curve in _defect_jobs(case):
                done(repair_job(case, job, curve))
    return rows
