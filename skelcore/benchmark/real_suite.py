"""The real suites (docs/benchmark.md, "The real suite: traced neurons"): the shipped traced neurons
(:mod:`.neurons`) sampled from their meshes, with their traced SWC skeletons as ground truth.

``real``: each of the five neurons at 30k, 100k and 300k points (``sizes`` picks some), clean and
under the default suite's one-sided views, noise, non-uniform density and outliers at every level of
:data:`.suite.EFFECT_LEVELS` (the scan effects of :mod:`.scan_effects`, scaled by the local radius:
a mesh sample's is its nearest SWC node's): 14 cases per neuron and size. ``real-small``: the first
neuron at 30k, clean (the tests). A case is ``{neuron}_{size}__clean`` or
``{neuron}_{size}__{effect}-{level}``, written in the layout of :mod:`.writer` (the reference is the
SWC with its radii, vertex order kept) plus ``truth/{neuron}_gt_facts.csv``, the per-node facts of
:func:`.neurons.node_facts`, one file per neuron. Seeds and resume work as for the generated suites.
"""

from __future__ import annotations

import hashlib
import zlib
from pathlib import Path
from typing import Any, Callable, Sequence

import numpy as np

from ..errors import SkelInputError
from ..version import __version__
from .neurons import NEURON_DIR, NEURON_IDS, MeshSampler, Neuron, load_neuron, node_facts, write_facts_csv
from .scan_effects import ScanEffects, scan
from .suite import EFFECT_LEVELS, GENERATOR_VERSION, _label, rng_for
from .writer import record_path, write_case_files, write_json, write_manifest

__all__ = ["REAL_SUITES", "REAL_SIZES", "REAL_EFFECTS", "RealCase", "real_cases", "facts_path", "make_real_benchmark"]

REAL_SUITES = ("real", "real-small")
#: the sizes of the real suite, in points (before one-sided views thin a scan, outliers added after)
REAL_SIZES = (30000, 100000, 300000)
#: the scan effects the real suite applies, each at every level of the default suite
REAL_EFFECTS = ("views", "noise", "nonuniform", "outliers")
#: bumped whenever a change to the real suite changes its output for the same seed and files
REAL_VERSION = 1

Progress = Callable[[int, int, str, str], None]


class RealCase:
    """One neuron at one size under one scan effect at one level (or clean)."""

    def __init__(self, neuron: str, size: int, effect: str, level: Any) -> None:
        self.neuron, self.size, self.effect, self.level = neuron, int(size), effect, level
        tag = f"{neuron}_{size // 1000}k" if size % 1000 == 0 else f"{neuron}_{size}"
        self.name = f"{tag}__clean" if effect == "clean" else f"{tag}__{effect}-{_label(effect, level)}"
        self.effects = ScanEffects(n_points=self.size) if effect == "clean" else \
            ScanEffects(n_points=self.size, **{effect: level})

    def seed(self, suite_seed: int) -> list[int]:
        return [int(suite_seed), zlib.crc32(self.name.encode())]

    def spec(self, suite_seed: int, digests: dict[str, str]) -> dict[str, Any]:
        """Everything the case's files depend on (compared on resume), the neuron's files by digest."""
        return {"generator": GENERATOR_VERSION, "real": REAL_VERSION, "neuron": self.neuron, "files": digests,
                "effect": self.effect, "level": self.level, "scan": self.effects.to_dict(),
                "scan_seed": self.seed(suite_seed)}


def real_cases(suite: str, sizes: Sequence[int] | None = None) -> list[RealCase]:
    """The cases of ``suite`` ("real" or "real-small") at ``sizes`` (default: the suite's), in a fixed order."""
    if suite == "real-small":
        return [RealCase(NEURON_IDS[0], s, "clean", None) for s in (sizes or (30000,))]
    if suite != "real":
        raise SkelInputError(f"unknown real suite {suite!r} (known: {', '.join(REAL_SUITES)})")
    cases = []
    for size in (sizes or REAL_SIZES):
        for nid in NEURON_IDS:
            cases.append(RealCase(nid, size, "clean", None))
            cases += [RealCase(nid, size, e, lv) for e in REAL_EFFECTS for lv in EFFECT_LEVELS[e]]
    return cases


def facts_path(folder: Path, neuron: str) -> Path:
    return folder / "truth" / f"{neuron}_gt_facts.csv"


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()[:16]


class _NeuronCache:
    """Each neuron's files, sampler and facts, loaded the first time a case needs them."""

    def __init__(self, folder: Path, source: Path) -> None:
        self.folder, self.source = folder, source
        self._neurons: dict[str, tuple[Neuron, MeshSampler, dict[str, Any]]] = {}

    def digests(self, nid: str) -> dict[str, str]:
        return {f"{nid}.{ext}": _digest(self.source / f"{nid}.{ext}") for ext in ("obj", "swc")}

    def get(self, nid: str) -> tuple[Neuron, MeshSampler, dict[str, Any]]:
        if nid not in self._neurons:
            neuron = load_neuron(nid, self.source)
            facts = node_facts(neuron)
            write_facts_csv(facts_path(self.folder, nid), neuron, facts)
            sampler = MeshSampler(neuron.mesh, neuron.skeleton.vertices, neuron.skeleton.radius)
            self._neurons[nid] = (neuron, sampler, facts.summary())
        return self._neurons[nid]


def _make_case(folder: Path, case: RealCase, spec: dict[str, Any], cache: _NeuronCache) -> dict[str, Any]:
    from .generate import _rounded, graph_summary

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


def make_real_benchmark(folder: Path, suite: str, seed: int, *, sizes: Sequence[int] | None = None,
                        force: bool = False, progress: Progress | None = None, source: Path | None = None):
    """Write real suite ``suite`` into ``folder`` as :func:`.generate.make_benchmark` writes the
    generated ones (resumable; ``suite.json`` and ``compare.toml`` rewritten from the records)."""
    from .generate import BenchResult, _claim, _finished, _remove_stale, _rounded

    if sizes is not None and (not sizes or any(int(s) < 1000 for s in sizes)):
        raise SkelInputError("sizes must be whole numbers of points >= 1000")
    source = Path(source) if source is not None else NEURON_DIR
    cases = real_cases(suite, sizes)
    remake, ours = _claim(folder, suite, seed, force)
    if remake and ours:
        _remove_stale(folder, {c.name for c in cases})
    (folder / "truth").mkdir(exist_ok=True)
    cache = _NeuronCache(folder, source)
    digests: dict[str, dict[str, str]] = {}
    records, made = [], 0
    for i, case in enumerate(cases, start=1):
        if case.neuron not in digests:
            digests[case.neuron] = cache.digests(case.neuron)
        spec = _rounded(case.spec(seed, digests[case.neuron]))
        rec = None if remake else _finished(folder, case, spec)  # type: ignore[arg-type]
        if rec is not None and not facts_path(folder, case.neuron).is_file():
            rec = None
        status = "kept" if rec is not None else "made"
        if rec is None:
            rec = _make_case(folder, case, spec, cache)
            made += 1
        records.append(rec)
        if progress is not None:
            progress(i, len(cases), case.name, status)
    doc = {"skelscope_bench": 1, "suite": suite, "seed": seed, "generator": GENERATOR_VERSION, "real": REAL_VERSION,
           "skelcore": __version__, "sizes": sorted({c.size for c in cases}), "cases": records}
    write_json(folder / "suite.json", doc)
    write_manifest(folder, records, suite, seed, notes=[
        "# Each case is a traced neuron's mesh sampled (resources/neurons, CC BY 4.0); its reference is the",
        "# proofread SWC skeleton with radii, not an exact medial axis: truth/{neuron}_gt_facts.csv says which",
        "# nodes lie outside the decimated mesh (docs/benchmark.md, the real suite).",
    ])
    return BenchResult(folder, suite, seed, made, len(cases) - made, records)
