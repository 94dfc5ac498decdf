"""Which metric sees which defect: ``skelcore bench validity --out DIR``.

On the benchmark's well-posed shapes (the suite's clean cases; the plate, whose curve skeleton is
ill-posed, is left out) the EXACT curve skeleton gets each controlled defect of :mod:`.skeleton_defects` at
each of its levels. The clean skeleton and every defective one are scored by every metric against a
fresh cloud of the shape per seed: the paper's four through ``skelcore.evaluate`` (curve skeleton,
and a skeletal set made of each cloud point's projection onto that curve, so index correspondence
holds), SkelScope's coverage, the diagnostics (their sizes and warnings), and the ground-truth
metrics against the exact skeleton (:func:`skelcore.metrics.ground_truth.compare_with_ground_truth`).

A task is one (shape, seed, defect): its levels share the shape's cloud. Tasks run on the pool or
Dask (:func:`skelcore.compare.backends.run_tasks`); each finished task is written atomically as
``tasks/{key}.json`` and a rerun skips the tasks whose file holds the same spec (resume).
:mod:`.validity_stats` turns the rows into detection AUCs and Spearman correlations,
:mod:`.validity_report` into the table and the heat-map.
"""

from __future__ import annotations

import functools
import os
import zlib
from dataclasses import dataclass, replace
from typing import Any, Callable

import numpy as np

from ..errors import SkelInputError
from ..params import Params
from ..version import __version__
from .neurons import NEURON_IDS
from .skeleton_defects import DEFECTS, apply_defect
from .task_store import TaskRun, read_rows, run_stored_tasks, task_path, task_record

__all__ = ["VALIDITY_SUITES", "ValiditySuite", "Task", "validity_tasks", "score_curve", "run_task", "run_validity",
           "task_path", "WARNING_CODES", "GT_KEYS", "COMMUNITY_KEYS", "read_rows", "TASK_VERSION"]

#: Bumped whenever a change alters a task's rows for the same spec (stored tasks are then redone).
TASK_VERSION = 2

#: the warning codes recorded per row as 0/1 columns ``warn_{code}``
WARNING_CODES = ("incomplete", "spurious_branches", "spurious_cycles", "missing_cycles", "outside", "collapse")

#: the ground-truth fields recorded per row as ``gt_{name}`` (docs/metrics.md 5.3.1)
GT_KEYS = ("f1", "precision", "recall", "chamfer_radii", "junction_precision", "junction_recall",
           "endpoint_precision", "endpoint_recall", "cycle_error", "length_ratio", "splits", "merges")
#: the other communities' ground-truth metrics recorded as ``gt_{name}`` (docs/metrics.md 5.3.2)
COMMUNITY_KEYS = ("diag_f1_1", "diag_f1_2", "diag_f1_5", "diag_precision_2", "diag_recall_2", "chamfer_diag",
                  "branch_precision", "branch_recall", "branch_f1", "dup_precision", "betti0_error", "betti1_error",
                  "radius_error", "esa", "dsa", "pds", "path_precision", "path_recall", "path_f1")


@dataclass(frozen=True)
class ValiditySuite:
    """Which shapes (benchmark suite names), how many points per cloud, how many seeds."""

    name: str
    shapes: tuple[str, ...]
    points: int
    seeds: int


VALIDITY_SUITES = {
    "small": ValiditySuite("small", ("junction_y", "torus", "tube_a"), 1200, 2),
    "default": ValiditySuite("default", ("tube_a", "tube_b", "elliptic", "junction_y", "junction_t", "junction_x",
                                         "tree_2", "tree_3", "tree_4", "torus", "genus2", "hand"), 5000, 3),
    # the real suite: the traced neurons of resources/neurons, their SWC the exact skeleton
    "neurons": ValiditySuite("neurons", NEURON_IDS, 3000, 1),
}


@dataclass(frozen=True)
class Task:
    """One (shape, seed, defect) of the study; defect "clean" is the exact skeleton itself."""

    shape: str
    seed: int
    defect: str
    points: int
    suite_seed: int

    @property
    def key(self) -> str:
        return f"{self.shape}__{self.defect}__s{self.seed}"

    def spec(self) -> dict[str, Any]:
        levels = [] if self.defect == "clean" else [list(x) if isinstance(x, tuple) else x
                                                    for x in DEFECTS[self.defect].levels]
        return {"task_version": TASK_VERSION, "shape": self.shape, "seed": self.seed, "defect": self.defect,
                "levels": levels, "points": self.points, "suite_seed": self.suite_seed}


def validity_tasks(suite: str = "default", *, seed: int = 0, seeds: int | None = None,
                   shapes: list[str] | None = None, defects: list[str] | None = None,
                   points: int | None = None) -> list[Task]:
    """The tasks of ``suite`` ("small" or "default"), optionally restricted to some shapes / defects,
    with another number of seeds or points; a one-line SkelInputError for an unknown name."""
    if suite not in VALIDITY_SUITES:
        raise SkelInputError(f"unknown suite {suite!r} (known: {', '.join(VALIDITY_SUITES)})")
    s = VALIDITY_SUITES[suite]
    from .suite import SHAPES

    known = list(NEURON_IDS) if suite == "neurons" else [n for n in SHAPES if n != "plate"]
    for name in shapes or ():
        if name not in known:
            raise SkelInputError(f"unknown shape {name!r} (known: {', '.join(known)})")
    for name in defects or ():
        if name not in DEFECTS:
            raise SkelInputError(f"unknown defect {name!r} (known: {', '.join(DEFECTS)})")
    n_seeds = s.seeds if seeds is None else int(seeds)
    if n_seeds < 1:
        raise SkelInputError(f"--seeds must be at least 1, got {n_seeds}")
    n_points = s.points if points is None else int(points)
    if n_points < 200:
        raise SkelInputError(f"--points must be at least 200, got {n_points}")
    names = ["clean", *(defects or DEFECTS)]
    return [Task(sh, k, d, n_points, int(seed)) for sh in (shapes or s.shapes) for k in range(n_seeds) for d in names]


# ---- one task ---------------------------------------------------------------------------------

#: a neuron's ground-truth metrics sample both curves every this many x its smallest radius (not
#: 0.1: a traced neuron is 25,000 of its thinnest radii long; docs/validity.md "The traced neurons")
NEURON_SAMPLE_STEP = 1.0


@dataclass(frozen=True)
class _Subject:
    """What a task needs of a shape or neuron: its family, sampler, exact skeleton and signed distance."""

    family: str
    sampler: Any
    reference: tuple[np.ndarray, np.ndarray, np.ndarray]
    surface: Callable[[np.ndarray], np.ndarray]
    sample_step: float  # the ground-truth metrics' sample step, in the reference's smallest radius


@functools.lru_cache(maxsize=2)
def _subject(name: str, suite_seed: int) -> _Subject:
    if name not in NEURON_IDS:
        from .tubes import signed_distance

        shape, sampler, ref = _shape(name, suite_seed)
        return _Subject(shape.family, sampler, ref, lambda p: signed_distance(shape, p, spacing=0.1),
                        Params.gt_sample_step)
    from ..correspondence import project_onto_curve
    from ..metrics.ground_truth import _at_projection
    from .neurons import MeshSampler, load_neuron

    neuron = load_neuron(name)
    sk = neuron.skeleton
    ref = (sk.vertices, sk.edges, np.asarray(sk.radius, float))

    def surface(p: np.ndarray) -> np.ndarray:
        """Signed distance to the traced tube (the SWC's nodes and radii; < 0 inside): the mesh and
        the tracing disagree on thin twigs, and a shortcut must leave the tracing's own tube."""
        q, qe = project_onto_curve(p, sk)
        return np.linalg.norm(q - p, axis=1) - _at_projection(sk, ref[2], q, qe)

    return _Subject("neuron", MeshSampler(neuron.mesh, sk.vertices, ref[2]), ref, surface, NEURON_SAMPLE_STEP)


@functools.lru_cache(maxsize=4)
def _shape(name: str, suite_seed: int):
    from .families import make_shape
    from .suite import SHAPES
    from .surface_sampling import SurfaceSampler
    from .tubes import reference_skeleton

    entry = SHAPES[name]
    shape = make_shape(name, entry.family, np.random.SeedSequence(entry.seed(suite_seed)), **entry.params)
    return shape, SurfaceSampler(shape), reference_skeleton(shape)


@functools.lru_cache(maxsize=4)
def _cloud(name: str, suite_seed: int, seed: int, points: int) -> np.ndarray:
    from .scan_effects import ScanEffects, scan

    sampler = _subject(name, suite_seed).sampler
    rng = np.random.default_rng(np.random.SeedSequence([suite_seed, zlib.crc32(f"validity/{name}".encode()), seed]))
    return scan(sampler, ScanEffects(n_points=points), rng).cloud


def _nan(x: Any) -> float:
    return float("nan") if x is None else float(x)


def score_curve(cloud: np.ndarray, vertices: np.ndarray, edges: np.ndarray, ref_v: np.ndarray, ref_e: np.ndarray,
                ref_r: np.ndarray, sample_step: float = Params.gt_sample_step) -> dict[str, float]:
    """Every metric of one curve: the evaluation's scores (Scores columns), the warnings as 0/1,
    the ground-truth metrics (``gt_*``, docs/metrics.md 5.3.1 and 5.3.2; the curve's radius for the
    radius error is the cloud's estimate at its vertices) and the ground-truth error ``gt_error`` = 1 - F1."""
    from ..correspondence import project_onto_curve
    from ..curve import CurveSkeleton
    from ..metrics.ground_truth import GroundTruthParams, compare_with_ground_truth, radius_from_cloud
    from ..metrics.gt_community import CommunityParams, community_metrics
    from ..scores import Scores
    from ..stages.orchestrate import evaluate

    curve = CurveSkeleton.from_raw(vertices, edges)
    skeletal, _ = project_onto_curve(cloud, curve)
    ev = evaluate(cloud, skeletal=skeletal, curve=curve)
    row: dict[str, float] = {k: _nan(v) for k, v in Scores.from_evaluation(ev).flat().items()}
    codes = {w.code for w in ev.warnings}
    row.update({f"warn_{c}": float(c in codes) for c in WARNING_CODES})
    reference = CurveSkeleton.from_raw(ref_v, ref_e)
    gt = compare_with_ground_truth(curve, reference, ref_r, params=GroundTruthParams(sample_step=sample_step))
    row.update({f"gt_{k}": float(getattr(gt, k)) for k in GT_KEYS})
    own_r = radius_from_cloud(curve.vertices, cloud, Params.gt_radius_k)
    more = community_metrics(curve, reference, ref_r, curve_radius=own_r,
                             params=replace(CommunityParams(), sample_step=sample_step))
    row.update({f"gt_{k}": float(more[k]) for k in COMMUNITY_KEYS})
    row["gt_error"] = 1.0 - float(gt.f1)
    row["n_vertices"], row["n_edges"] = float(curve.n_vertices), float(curve.n_edges)
    return row


def _task_rows(task: Task) -> list[dict[str, Any]]:
    subject = _subject(task.shape, task.suite_seed)
    ref_v, ref_e, ref_r = subject.reference
    cloud = _cloud(task.shape, task.suite_seed, task.seed, task.points)
    base = {"shape": task.shape, "family": subject.family, "seed": task.seed, "defect": task.defect}
    if task.defect == "clean":
        return [{**base, "level": "", "level_index": 0, **score_curve(cloud, ref_v, ref_e, ref_v, ref_e, ref_r,
                                                                     subject.sample_step)}]
    d = DEFECTS[task.defect]
    rows = []
    for i, level in enumerate(d.levels, start=1):
        label = d.label(level)
        rng = np.random.default_rng(np.random.SeedSequence(
            [task.suite_seed, zlib.crc32(f"{task.shape}/{task.defect}/{label}".encode()), task.seed]))
        made = apply_defect(task.defect, level, ref_v, ref_e, ref_r, rng, subject.surface)
        if made is None or len(made[1]) == 0:
            continue  # the defect does not apply to this shape (or leaves nothing)
        rows.append({**base, "level": label, "level_index": i, **score_curve(cloud, *made, ref_v, ref_e, ref_r,
                                                                                subject.sample_step)})
    return rows


def run_task(task: Task) -> dict[str, Any]:
    """A task's record (runs in a worker): its spec, status, rows, seconds; an error is one line."""
    return task_record(task, _task_rows)


# ---- the run ----------------------------------------------------------------------------------

def run_validity(out: str | os.PathLike, tasks: list[Task], backend: Any, *, force: bool = False,
                 figure: bool = True, progress: Callable[[int, int, str, str], None] | None = None,
                 suite: str = "default") -> TaskRun:
    """Run (or resume) ``tasks`` into ``out`` on ``backend`` (:class:`skelcore.compare.backends.Backend`)
    and write ``scores.csv``, ``validity.csv``, ``validity.md`` and ``validity.png`` there; the statistics
    tables written are the result's ``tables`` (computed once: their bootstraps and permutation tests are
    most of a resumed run's time)."""
    from ..compare.run_marker import claim_run_folder
    from .validity_report import write_report

    folder = claim_run_folder(out, "validity", force=force).path
    result = run_stored_tasks(folder, tasks, run_task, backend, progress)
    for rec in write_report(folder, result.rows, figure=figure,
                            note=f"{suite} suite, {len(tasks)} tasks, skelcore {__version__}"):
        result.tables.setdefault(rec["set"], []).append(rec)
    return result
