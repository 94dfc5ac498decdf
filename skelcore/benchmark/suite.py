"""The benchmark suites: which shapes, which scan effects at which levels, and each case's seeds.

A case is one shape under one scan effect at one level (or clean), named
``{shape}__{effect}-{level}`` (``{shape}__clean``). ``default``: every shape clean at 5000 points,
and five probe shapes (a random tube, the Y junction, the 3-level tree, the torus, the hand) under
every effect at every level (density 1k and 20k on each probe, 50k and 200k on the tree): 120 cases,
a few minutes of ``skelcore compare`` with cao on 2 cores. ``small``: 10 cases of about 1200 points,
for the tests. Seeds: a shape's geometry is drawn from ``SeedSequence([seed, crc32(shape)])`` and a
case's scan from ``SeedSequence([seed, crc32(case)])``, so every case can be remade alone (resume)
and the cases of one shape share its geometry.
"""

from __future__ import annotations

import zlib
from dataclasses import dataclass, field
from typing import Any

import numpy as np

from .scan_effects import ScanEffects

__all__ = ["ShapeEntry", "Case", "SHAPES", "SUITES", "suite_cases", "EFFECT_LEVELS", "GENERATOR_VERSION", "rng_for"]

#: Bumped whenever a change to the generator changes its output for the same seed.
GENERATOR_VERSION = 1


@dataclass(frozen=True)
class ShapeEntry:
    """A named shape instance: a family of :mod:`.families` with its parameters."""

    name: str
    family: str
    params: dict[str, Any] = field(default_factory=dict)

    def seed(self, suite_seed: int) -> list[int]:
        return [int(suite_seed), zlib.crc32(self.name.encode())]


@dataclass(frozen=True)
class Case:
    name: str
    shape: ShapeEntry
    effect: str
    level: Any
    effects: ScanEffects

    def seed(self, suite_seed: int) -> list[int]:
        return [int(suite_seed), zlib.crc32(self.name.encode())]

    def spec(self, suite_seed: int) -> dict[str, Any]:
        """Everything the case's files depend on (compared on resume)."""
        return {"generator": GENERATOR_VERSION, "shape": self.shape.name, "family": self.shape.family,
                "shape_params": self.shape.params, "shape_seed": self.shape.seed(suite_seed),
                "effect": self.effect, "level": self.level, "scan": self.effects.to_dict(),
                "scan_seed": self.seed(suite_seed)}


SHAPES = {s.name: s for s in (
    ShapeEntry("tube_a", "tube"),
    ShapeEntry("tube_b", "tube", {"radius": 0.12, "variation": 0.4, "steps": 8}),
    ShapeEntry("elliptic", "elliptic"),
    ShapeEntry("junction_y", "junction", {"kind": "y"}),
    ShapeEntry("junction_t", "junction", {"kind": "t"}),
    ShapeEntry("junction_x", "junction", {"kind": "x"}),
    ShapeEntry("tree_2", "tree", {"levels": 2}),
    ShapeEntry("tree_3", "tree", {"levels": 3}),
    ShapeEntry("tree_4", "tree", {"levels": 4}),
    ShapeEntry("torus", "torus"),
    ShapeEntry("genus2", "genus2"),
    ShapeEntry("hand", "hand"),
    ShapeEntry("plate", "plate"),
)}

#: Each effect's graded levels (mild to strong) and the ScanEffects field(s) a level sets.
EFFECT_LEVELS: dict[str, list[Any]] = {
    "noise": [0.02, 0.05, 0.1, 0.2],          # sigma per coordinate, in local radii
    "density": [1000, 20000, 50000, 200000],  # points (the base is 5000)
    "nonuniform": [3.0, 10.0, 30.0],          # density ratio across the shape
    "views": [1, 2, 3],                       # one-sided scan from this many viewpoints
    "holes": [(3, 0.5), (6, 0.8), (12, 1.0)],  # (count, radius in local radii)
    "outliers": [0.01, 0.05, 0.2],            # fraction of the points added
    "crop": [0.1, 0.25, 0.4],                 # fraction of the points cut away by a plane
}


def _effects(effect: str, level: Any, base: int) -> ScanEffects:
    if effect == "clean":
        return ScanEffects(n_points=base)
    if effect == "density":
        return ScanEffects(n_points=int(level))
    if effect == "holes":
        return ScanEffects(n_points=base, holes=int(level[0]), hole_radius=float(level[1]))
    return ScanEffects(n_points=base, **{effect: level})


def _label(effect: str, level: Any) -> str:
    if effect == "density":
        return f"{int(level) // 1000}k" if level % 1000 == 0 else str(level)
    if effect == "nonuniform":
        return f"{level:g}x"
    if effect == "holes":
        return f"{level[0]}x{level[1]:g}"
    return f"{level:g}"


def _case(shape: str, effect: str, level: Any, base: int) -> Case:
    name = f"{shape}__clean" if effect == "clean" else f"{shape}__{effect}-{_label(effect, level)}"
    stored = list(level) if isinstance(level, tuple) else level
    return Case(name, SHAPES[shape], effect, stored, _effects(effect, level, base))


def _default() -> list[Case]:
    base = 5000
    cases = [_case(s, "clean", None, base) for s in SHAPES]
    for probe in ("tube_a", "junction_y", "tree_3", "torus", "hand"):
        for effect, levels in EFFECT_LEVELS.items():
            for level in levels:
                if effect == "density" and level > 20000 and probe != "tree_3":
                    continue
                cases.append(_case(probe, effect, level, base))
    return cases


def _small() -> list[Case]:
    base = 1200
    cases = [_case(s, "clean", None, base) for s in ("junction_y", "torus", "tube_a", "plate")]
    cases += [_case("junction_y", "noise", 0.05, base), _case("junction_y", "views", 1, base),
              _case("junction_y", "crop", 0.25, base), _case("torus", "holes", (3, 0.5), base),
              _case("torus", "outliers", 0.05, base), _case("tube_a", "nonuniform", 10.0, base)]
    return cases


SUITES = {"default": _default, "small": _small}


def suite_cases(suite: str) -> list[Case]:
    """The cases of suite ``suite`` ("default" or "small"), in a fixed order."""
    if suite not in SUITES:
        raise ValueError(f"unknown suite {suite!r} (known: {', '.join(SUITES)})")
    cases = SUITES[suite]()
    assert len({c.name for c in cases}) == len(cases)
    return cases


def rng_for(seed: list[int]) -> np.random.Generator:
    """The generator of a shape or case seed (a list of integers, as written to suite.json)."""
    return np.random.default_rng(np.random.SeedSequence(seed))
