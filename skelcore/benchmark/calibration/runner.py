"""Run the calibration's tasks on the pool of ``skelcore compare`` (resume: a task whose stored file
holds the same spec is kept), then write the report (:mod:`.report`)."""

from __future__ import annotations

import json
import os
import time
from typing import Any, Callable

import numpy as np

from ..task_store import TaskRun, read_rows, run_stored_tasks, task_path, task_record
from .grid import CODES, Task

__all__ = ["run_task", "evaluate_kind", "run_calibration", "read_rows", "task_path"]


def evaluate_kind(task: Task, w, kind: str, first: bool, drop: float | None = None) -> dict[str, Any] | None:
    """One skeleton kind on the task's cloud: the codes fired and the truth per code (None when the
    kind does not apply to this shape); ``drop``: the sparse part's toll on boundedness (truth.sparse_drop)."""
    from ...curve import CurveSkeleton
    from ...stages.orchestrate import evaluate
    from .skeletons import make_kind
    from .truth import row_truth

    made = make_kind(kind, w, f"{task.shape}/{task.size}/{task.condition}", task.suite_seed)
    if made is None:
        return None
    t0 = time.perf_counter()
    ev = evaluate(w.cloud, skeletal=made.skeletal, curve=CurveSkeleton.from_raw(made.vertices, made.edges), workers=1)
    seconds = time.perf_counter() - t0
    fired = {wn.code for wn in ev.warnings}
    arrays = ev.diagnostics.arrays if getattr(ev, "diagnostics", None) is not None else {}
    row = {"suite": task.suite, "shape": task.shape, "size": task.size, "points": int(len(w.cloud)),
           "condition": task.condition, "kind": kind, "level": json.dumps(made.level),
           "fired": ";".join(sorted(fired)), "seconds": round(seconds, 3)}
    row.update({f"fired_{c}": int(c in fired) for c in CODES})
    row.update(row_truth(made, w, task.condition, fired, arrays, first, drop=drop))
    return {k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in row.items()}


def run_task(task: Task) -> dict[str, Any]:
    """A task's record (runs in a worker): spec, status, rows, seconds; an error is one line."""
    return task_record(task, _task_rows)


def _task_rows(task: Task) -> list[dict[str, Any]]:
    from .skeletons import world

    w = world(task.suite, task.shape, task.size, task.condition, task.suite_seed)
    drop = None
    if task.condition == "nonuniform":  # the truth of sparse_boundedness: against the uniform cloud
        from .truth import sparse_drop

        drop = sparse_drop(w, world(task.suite, task.shape, task.size, "clean", task.suite_seed).cloud)
    rows = []
    for i, kind in enumerate(task.kinds):
        row = evaluate_kind(task, w, kind, first=(i == 0), drop=drop)
        if row is not None:
            rows.append(row)
    return rows


def run_calibration(out: str | os.PathLike, tasks: list[Task], backend: Any, *, force: bool = False,
                    progress: Callable[[int, int, str, str], None] | None = None, command: str = "",
                    machine: str = "") -> TaskRun:
    """Run (or resume) ``tasks`` into ``out`` on ``backend`` and write ``calibration.csv``,
    ``rows.csv`` and ``calibration.md`` there (:func:`.calib_tables.write_report`)."""
    from ...compare.run_marker import claim_run_folder
    from .calib_tables import write_report

    folder = claim_run_folder(out, "calibrate", force=force).path
    result = run_stored_tasks(folder, tasks, run_task, backend, progress)
    write_report(folder, result.rows, command=command, machine=machine, wall=result.wall)
    return result
