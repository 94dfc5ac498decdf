"""The real suites (docs/benchmark.md, "The real suite: traced neurons"): the shipped traced neurons
(:mod:`.neurons`) sampled from their meshes, with their traced SWC skeletons as ground truth.

``real``: each of the five neurons at 30k, 100k and 300k points (``sizes`` picks some), clean and
under the default suite's one-sided views, noise, non-uniform density and outliers at every level of
:data:`.suite.EFFECT_LEVELS` (the scan effects of :mod:`.scan_effects`, scaled by the local radius:
a mesh sample's is its nearest SWC node's): 14 cases per neuron and size. ``real-small``: the first
neuron at 30k, clean (the tests). A case is ``{neuron}_{size}__clean`` or
``{neuron}_{size}__{effect}-{level}``, written in the layout of :mod:`.writer` (the reference is the
SWC with its radii, vertex order kept) plus ``truth/{neuron}_gt_facts.csv``, the per-node facts of
:func:`.neurons.node_facts`, one file per neuron. Seeds and resume work as for the generated suites
(:func:`.generate.make_benchmark` makes both).
"""

from __future__ import annotations

import hashlib
import zlib
from pathlib import Path
from typing import Any, Sequence

from ..errors import SkelInputError
from .neurons import NEURON_DIR, NEURON_IDS, MeshSampler, Neuron, load_neuron, node_facts, write_facts_csv
from .scan_effects import ScanEffects
from .suite import EFFECT_LEVELS, GENERATOR_VERSION, _label
from .writer import facts_path

__all__ = ["REAL_SUITES", "REAL_SIZES", "REAL_EFFECTS", "REAL_VERSION", "RealCase", "real_cases", "NeuronCache",
           "MANIFEST_NOTES"]

REAL_SUITES = ("real", "real-small")
#: the sizes of the real suite, in points (before one-sided views thin a scan, outliers added after)
REAL_SIZES = (30000, 100000, 300000)
#: the scan effects the real suite applies, each at every level of the default suite
REAL_EFFECTS = ("views", "noise", "nonuniform", "outliers")
#: bumped whenever a change to the real suite changes its output for the same seed and files
REAL_VERSION = 1

#: compare.toml's note on the real suites' references
MANIFEST_NOTES = [
    "# Each case is a traced neuron's mesh sampled (resources/neurons, CC BY 4.0); its reference is the",
    "# proofread SWC skeleton with radii, not an exact medial axis: truth/{neuron}_gt_facts.csv says which",
    "# nodes lie outside the decimated mesh (docs/benchmark.md, the real suite).",
]


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


def _digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()[:16]


class NeuronCache:
    """Each neuron's files, sampler and facts, loaded the first time a case needs them."""

    def __init__(self, folder: Path, source: Path = NEURON_DIR) -> None:
        self.folder, self.source = folder, source
        self._neurons: dict[str, tuple[Neuron, MeshSampler, dict[str, Any]]] = {}
        self._digests: dict[str, dict[str, str]] = {}

    def digests(self, nid: str) -> dict[str, str]:
        """The neuron's two files by their SHA-256 (a case's spec: a changed file remakes its cases)."""
        if nid not in self._digests:
            for ext in ("obj", "swc"):
                if not (self.source / f"{nid}.{ext}").is_file():
                    raise SkelInputError("not found: the real suites read resources/neurons of SkelScope's source "
                                         "tree (the sdist or a checkout; the wheel does not ship it)",
                                         self.source / f"{nid}.{ext}")
            self._digests[nid] = {f"{nid}.{ext}": _digest(self.source / f"{nid}.{ext}") for ext in ("obj", "swc")}
        return self._digests[nid]

    def get(self, nid: str) -> tuple[Neuron, MeshSampler, dict[str, Any]]:
        if nid not in self._neurons:
            neuron = load_neuron(nid, self.source)
            facts = node_facts(neuron)
            write_facts_csv(facts_path(self.folder, nid), neuron, facts)
            sampler = MeshSampler(neuron.mesh, neuron.skeleton.vertices, neuron.skeleton.radius)
            self._neurons[nid] = (neuron, sampler, facts.summary())
        return self._neurons[nid]
