"""``make_benchmark``: write a suite's cases into a folder, resumably, refusing a folder that is not
a benchmark.

The folder must be new, empty, or a benchmark of the same suite, seed and generator (its
``.skelscope-run`` marker of kind "bench" says so: :mod:`skelcore.compare.run_marker`, as for compare's
runs); anything else is one line naming it, unless ``force``, which (re)makes every case there and
replaces files of the same names. A case is remade unless its record exists, matches its
spec and its two files are there, so an interrupted run resumes where it stopped. ``suite.json`` and
``compare.toml`` are rewritten at the end from the records. A crop case's reference is clipped to the
kept half-space (the region scanned); every other case keeps the whole shape's skeleton (the object is
all there, the scan misses some of it). The real suites (traced neurons, :mod:`.real_suite`) go the
same way, their cases made by :func:`_make_real_case` from a mesh sampler and the SWC.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import SkelInputError
from ..version import __version__
from .families import make_shape
from .scan_effects import scan
from .suite import GENERATOR_VERSION, Case, rng_for, suite_cases
from .surface_sampling import SurfaceSampler
from .tubes import BenchShape, reference_skeleton
from ..compare.run_marker import claim_run_folder
from .real_suite import MANIFEST_NOTES, REAL_SUITES, REAL_VERSION, NeuronCache, RealCase, real_cases
from .writer import (cloud_path, facts_path, read_json, record_path, reference_path, write_case_files, write_json,
                     write_manifest)

__all__ = ["BenchResult", "make_benchmark", "clip_curve", "graph_summary", "KIND"]

#: the kind of run a benchmark folder is (its ``.skelscope-run`` marker, :mod:`skelcore.compare.run_marker`)
KIND = "bench"

Progress = Callable[[int, int, str, str], None]


@dataclass(frozen=True)
class BenchResult:
    folder: Path
    suite: str
    seed: int
    made: int
    kept: int
    records: list[dict[str, Any]]


def clip_curve(vertices: np.ndarray, edges: np.ndarray, radius: np.ndarray, normal: np.ndarray,
               offset: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """The part of a polyline graph where x . normal <= offset: edges crossing the plane end on it
    (radius interpolated); vertices beyond it are dropped."""
    s = vertices @ normal - offset
    inside = s <= 0
    a, b = edges[:, 0], edges[:, 1]
    both = inside[a] & inside[b]
    cross = inside[a] != inside[b]
    t = s[a[cross]] / (s[a[cross]] - s[b[cross]])
    new_v = vertices[a[cross]] + t[:, None] * (vertices[b[cross]] - vertices[a[cross]])
    new_r = radius[a[cross]] + t * (radius[b[cross]] - radius[a[cross]])
    kept_end = np.where(inside[a[cross]], a[cross], b[cross])
    n = len(vertices)
    all_v = np.vstack([vertices, new_v])
    all_r = np.concatenate([radius, new_r])
    all_e = np.vstack([edges[both], np.column_stack([kept_end, n + np.arange(len(new_v))])])
    used = np.unique(all_e.ravel())
    remap = np.full(len(all_v), -1)
    remap[used] = np.arange(len(used))
    return all_v[used], remap[all_e].astype(np.int64), all_r[used]


def graph_summary(vertices: np.ndarray, edges: np.ndarray, radius: np.ndarray) -> dict[str, Any]:
    """Counts of a reference (written to the case records)."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components

    n = len(vertices)
    deg = np.bincount(edges.ravel(), minlength=n)
    adj = coo_matrix((np.ones(len(edges)), (edges[:, 0], edges[:, 1])), shape=(n, n))
    comps = int(connected_components(adj, directed=False)[0])
    length = float(np.linalg.norm(vertices[edges[:, 1]] - vertices[edges[:, 0]], axis=1).sum())
    return {"vertices": n, "edges": int(len(edges)), "junctions": int(np.sum(deg >= 3)),
            "endpoints": int(np.sum(deg == 1)), "components": comps, "cycles": int(len(edges) - n + comps),
            "length": round(length, 9), "radius_min": round(float(radius.min()), 9),
            "radius_max": round(float(radius.max()), 9)}


def _claim(folder: Path, suite: str, seed: int, force: bool) -> tuple[bool, bool]:
    """Make ``folder`` our benchmark or check that it is (:func:`skelcore.compare.run_marker.claim_run_folder`,
    kind "bench", the suite, seed and generator in the marker): (remake every case, it was ours before)."""
    details = {"suite": suite, "seed": int(seed), "generator": GENERATOR_VERSION}
    claim = claim_run_folder(folder, KIND, force=force, details=details)
    return force, claim.previous is not None


def _remove_stale(folder: Path, names: set[str]) -> None:
    """Remove the files of cases we made earlier that the suite being made does not have (only ours:
    each is named by one of our case records)."""
    cases = folder / "cases"
    if not cases.is_dir():
        return
    for rec_file in sorted(cases.glob("*.json")):
        name = rec_file.stem
        if name in names or not isinstance(read_json(rec_file), dict):
            continue
        for p in (cloud_path(folder, name), reference_path(folder, name), rec_file):
            p.unlink(missing_ok=True)


def _finished(folder: Path, case: Case, spec: dict[str, Any]) -> dict[str, Any] | None:
    rec = read_json(record_path(folder, case.name))
    if not isinstance(rec, dict) or rec.get("spec") != spec:
        return None
    if not (cloud_path(folder, case.name).is_file() and reference_path(folder, case.name).is_file()):
        return None
    return rec


def _make_case(folder: Path, case: Case, spec: dict[str, Any], shape: BenchShape, sampler: SurfaceSampler) -> dict:
    result = scan(sampler, case.effects, rng_for(spec["scan_seed"]))
    v, e, r = reference_skeleton(shape)
    clipped = None
    if result.crop_plane is not None:
        v, e, r = clip_curve(v, e, r, *result.crop_plane)
        clipped = "clipped to the crop plane (the scanned region)"
    write_case_files(folder, case.name, result.cloud, v, e, r)
    info = {k: (round(x, 9) if isinstance(x, float) else x) for k, x in result.info.items()}
    record = {
        "name": case.name, "shape": shape.name, "family": shape.family, "effect": case.effect, "level": case.level,
        "curve_skeleton": shape.ill_posed or "exact",
        "files": {"cloud": f"clouds/{case.name}.ply", "reference": f"truth/{case.name}_reference.ply"},
        "points": int(len(result.cloud)), "scan": _rounded(info),
        "reference": {**graph_summary(v, e, r), "note": clipped or "the whole shape's curve skeleton"},
        "spec": spec,
    }
    write_json(record_path(folder, case.name), record)
    return record


def _rounded(x: Any) -> Any:
    if isinstance(x, float):
        return round(x, 9)
    if isinstance(x, dict):
        return {k: _rounded(v) for k, v in x.items()}
    if isinstance(x, (list, tuple)):
        return [_rounded(v) for v in x]
    return x


def make_benchmark(folder: str | os.PathLike, suite: str = "default", seed: int = 0, *, force: bool = False,
                   progress: Progress | None = None, sizes: Sequence[int] | None = None) -> BenchResult:
    """Write suite ``suite`` drawn from ``seed`` into ``folder`` (module docstring); ``progress(i,
    total, case, status)`` is called after each case, status "made" or "kept". The real suites
    ("real", "real-small": traced neurons, :mod:`.real_suite`) take ``sizes``, their clouds' sizes."""
    if suite not in ("default", "small", *REAL_SUITES):
        raise SkelInputError(f"unknown suite {suite!r} (default, small, {', '.join(REAL_SUITES)})")
    if not isinstance(seed, int) or seed < 0:
        raise SkelInputError(f"seed must be a whole number >= 0, got {seed!r}")
    if suite in REAL_SUITES:
        return _make_real(Path(folder), suite, seed, sizes, force, progress)
    if sizes is not None:
        raise SkelInputError(f"sizes apply to the real suites only, not to {suite!r}")
    cases = suite_cases(suite)
    folder = Path(folder)
    remake, ours = _claim(folder, suite, seed, force)
    shapes: dict[str, tuple[BenchShape, SurfaceSampler]] = {}
    records, made = [], 0
    if remake and ours:
        _remove_stale(folder, {c.name for c in cases})
    for i, case in enumerate(cases, start=1):
        spec = _rounded(case.spec(seed))
        rec = None if remake else _finished(folder, case, spec)
        status = "kept" if rec is not None else "made"
        if rec is None:
            if case.shape.name not in shapes:
                shape = make_shape(case.shape.name, case.shape.family, np.random.SeedSequence(spec["shape_seed"]),
                                   **case.shape.params)
                shapes[case.shape.name] = (shape, SurfaceSampler(shape))
            rec = _make_case(folder, case, spec, *shapes[case.shape.name])
            made += 1
        records.append(rec)
        if progress is not None:
            progress(i, len(cases), case.name, status)
    doc = {"skelscope_bench": 1, "suite": suite, "seed": seed, "generator": GENERATOR_VERSION,
           "skelcore": __version__, "cases": records}
    write_json(folder / "suite.json", doc)
    write_manifest(folder, records, suite, seed)
    return BenchResult(folder, suite, seed, made, len(cases) - made, records)


def _make_real_case(folder: Path, case: RealCase, spec: dict[str, Any], cache: NeuronCache) -> dict[str, Any]:
    """A real suite's case (:mod:`.real_suite`): the neuron's mesh scanned, its SWC as the reference."""
    neuron, sampler, facts = cache.get(case.neuron)
    result = scan(sampler, case.effects, rng_for(spec["scan_seed"]))
    sk = neuron.skeleton
    write_case_files(folder, case.name, result.cloud, sk.vertices, sk.edges, sk.radius)
    record = {
        "name": case.name, "shape": case.neuron, "family": "neuron", "effect": case.effect, "level": case.level,
        "size": case.size, "curve_skeleton": "traced", "tree": True,
        "files": {"cloud": f"clouds/{case.name}.ply", "reference": f"truth/{case.name}_reference.ply",
                  "facts": f"truth/{case.neuron}_gt_facts.csv"},
        "points": int(len(result.cloud)), "scan": _rounded(result.info),
        "reference": {**graph_summary(sk.vertices, sk.edges, sk.radius),
                      "note": "the proofread SWC skeleton (not an exact medial axis; nodes outside the decimated mesh: "
                              "see gt_facts)"},
        "gt_facts": facts, "spec": spec,
    }
    write_json(record_path(folder, case.name), record)
    return record


def _make_real(folder: Path, suite: str, seed: int, sizes: Sequence[int] | None, force: bool,
               progress: Progress | None) -> BenchResult:
    """``make_benchmark`` for the real suites: the same claim, resume and files (:mod:`.real_suite`)."""
    if sizes is not None and (not sizes or any(int(s) < 1000 for s in sizes)):
        raise SkelInputError("sizes must be whole numbers of points >= 1000")
    cases = real_cases(suite, sizes)
    remake, ours = _claim(folder, suite, seed, force)
    if remake and ours:
        _remove_stale(folder, {c.name for c in cases})
    (folder / "truth").mkdir(exist_ok=True)
    cache = NeuronCache(folder)
    records, made = [], 0
    for i, case in enumerate(cases, start=1):
        spec = _rounded(case.spec(seed, cache.digests(case.neuron)))
        rec = None if remake else _finished(folder, case, spec)  # type: ignore[arg-type]
        if rec is not None and not facts_path(folder, case.neuron).is_file():
            rec = None
        status = "kept" if rec is not None else "made"
        if rec is None:
            rec = _make_real_case(folder, case, spec, cache)
            made += 1
        records.append(rec)
        if progress is not None:
            progress(i, len(cases), case.name, status)
    doc = {"skelscope_bench": 1, "suite": suite, "seed": seed, "generator": GENERATOR_VERSION, "real": REAL_VERSION,
           "skelcore": __version__, "sizes": sorted({c.size for c in cases}), "cases": records}
    write_json(folder / "suite.json", doc)
    write_manifest(folder, records, suite, seed, notes=MANIFEST_NOTES)
    return BenchResult(folder, suite, seed, made, len(cases) - made, records)

