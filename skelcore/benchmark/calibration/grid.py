"""The calibration's tasks: one cloud (suite, shape, size, scan condition) and the skeleton kinds
evaluated on it. The clouds are those of ``skelcore bench make`` for the same seed: a generated
shape's case ``{shape}__{effect}-{level}`` at 5000 points, a neuron's ``{id}_{size}k__...``."""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Sequence

from ...errors import SkelInputError

__all__ = ["CODES", "CONDITIONS", "KINDS", "SUITES", "Task", "calibration_tasks", "TASK_VERSION"]

#: bumped whenever a change alters a task's rows for the same spec (stored tasks are then redone)
TASK_VERSION = 6

#: every warning code the evaluation emits, in the tables' order
CODES = ("spurious_branches", "spurious_cycles", "missing_cycles", "outside", "incomplete", "disconnected",
         "collapse", "frame", "outliers", "open_surface", "thin_parts", "sparse_boundedness", "trivial_smoothness",
         "no_correspondence", "along_surface")

#: the scan conditions: the benchmark's effect and level (docs/benchmark.md), clean first
CONDITIONS: dict[str, tuple[str, Any]] = {
    "clean": ("clean", None), "noise": ("noise", 0.05), "nonuniform": ("nonuniform", 10.0),
    "views": ("views", 1), "outliers": ("outliers", 0.05),
}

#: the skeleton kinds per (suite, condition): the intact skeleton and the injected defects
KINDS: dict[tuple[str, str], tuple[str, ...]] = {
    ("synthetic", "clean"): ("intact", "spurs", "shortcut", "chord_cycle", "broken_cycle", "missing_branch",
                             "truncation", "collapse", "frame", "nodes_only", "no_correspondence", "broken",
                             "offset"),
    ("synthetic", "other"): ("intact", "spurs", "broken"),
    ("real", "clean"): ("intact", "spurs", "shortcut", "chord_cycle", "missing_branch", "broken"),
    ("real", "other"): ("intact", "broken"),
}


@dataclass(frozen=True)
class SuiteSpec:
    """Which shapes, at which sizes (points), under which conditions."""

    kind: str
    shapes: tuple[str, ...]
    sizes: tuple[int, ...]
    conditions: tuple[str, ...]


SUITES: dict[str, SuiteSpec] = {
    "synthetic": SuiteSpec("synthetic", ("tube_a", "tube_b", "elliptic", "junction_y", "junction_t", "junction_x",
                                         "tree_2", "tree_3", "tree_4", "torus", "genus2", "hand"),
                           (5000,), tuple(CONDITIONS)),
    "synthetic-small": SuiteSpec("synthetic", ("junction_y", "torus"), (1200,), ("clean",)),
    "real": SuiteSpec("real", ("722817260", "754534424", "754538881", "1734350788", "1734350908"),
                      (30000,), tuple(CONDITIONS)),
    "real-small": SuiteSpec("real", ("722817260",), (30000,), ("clean",)),
}


@dataclass(frozen=True)
class Task:
    """One cloud and its skeleton kinds; ``suite`` is "synthetic" or "real"."""

    suite: str
    shape: str
    size: int
    condition: str
    kinds: tuple[str, ...]
    suite_seed: int = 0

    @property
    def key(self) -> str:
        return f"{self.suite}__{self.shape}__{self.size}__{self.condition}"

    def spec(self) -> dict[str, Any]:
        return {"task_version": TASK_VERSION, "suite": self.suite, "shape": self.shape, "size": self.size,
                "condition": self.condition, "kinds": list(self.kinds), "suite_seed": self.suite_seed}


def kinds_for(suite: str, condition: str) -> tuple[str, ...]:
    """The skeleton kinds evaluated on a cloud of ``suite`` under ``condition``."""
    return KINDS[(suite, "clean" if condition == "clean" else "other")]


def calibration_tasks(suites: Sequence[str], *, sizes: Sequence[int] | None = None,
                      points: Sequence[int] | None = None, shapes: Sequence[str] | None = None, conditions: Sequence[str] | None = None,
                      kinds: Sequence[str] | None = None, seed: int = 0) -> list[Task]:
    """The tasks of ``suites`` (names of :data:`SUITES`): the real suites at ``sizes``, the synthetic
    ones at ``points`` (default: the suite's), optionally fewer shapes, conditions or kinds; a
    one-line SkelInputError for an unknown name."""
    tasks = []
    known_shapes = {x for name in suites if name in SUITES for x in SUITES[name].shapes}
    for x in shapes or ():
        if x not in known_shapes:
            raise SkelInputError(f"unknown shape {x!r} for these suites (known: {', '.join(sorted(known_shapes))})")
    for name in suites:
        if name not in SUITES:
            raise SkelInputError(f"unknown suite {name!r} (known: {', '.join(SUITES)})")
        s = SUITES[name]
        for c in conditions or ():
            if c not in CONDITIONS:
                raise SkelInputError(f"unknown condition {c!r} (known: {', '.join(CONDITIONS)})")
        known = {k for key, ks in KINDS.items() for k in ks}
        for k in kinds or ():
            if k not in known:
                raise SkelInputError(f"unknown skeleton kind {k!r} (known: {', '.join(sorted(known))})")
        picked = [x for x in s.shapes if not shapes or x in shapes]
        for size in ((sizes if s.kind == "real" else points) or s.sizes):
            if int(size) < 1000:
                raise SkelInputError(f"sizes must be whole numbers of points >= 1000, got {size}")
            for shape in picked:
                for cond in (c for c in s.conditions if not conditions or c in conditions):
                    ks = tuple(k for k in kinds_for(s.kind, cond) if not kinds or k in kinds)
                    if ks:
                        tasks.append(Task(s.kind, shape, int(size), cond, ks, int(seed)))
    if not tasks:
        raise SkelInputError("no task left: the shapes, conditions and kinds given select nothing")
    return sorted(tasks, key=lambda t: (t.suite != "real", -len(t.kinds)))  # the longest first: a balanced pool
