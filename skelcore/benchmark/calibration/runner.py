"""Run the calibration's tasks on the pool of ``skelcore compare`` (resume: a task whose stored file
holds the same spec is kept), then write the report (:mod:`.report`)."""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

import numpy as np

from .grid import CODES, Task

__all__ = ["CalibrationResult", "run_task", "evaluate_kind", "run_calibration", "read_rows", "task_path"]


def evaluate_kind(task: Task, w, kind: str, first: bool) -> dict[str, Any] | None:
    """One skeleton kind on the task's cloud: the codes fired and the truth per code (None when the
    kind does not apply to this shape)."""
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
    row.update(row_truth(made, w, task.condition, fired, arrays, first))
    return {k: (None if isinstance(v, float) and not np.isfinite(v) else v) for k, v in row.items()}


def run_task(task: Task) -> dict[str, Any]:
    """A task's record (runs in a worker): spec, status, rows, seconds; an error is one line."""
    from .skeletons import world

    t0 = time.perf_counter()
    try:
        w = world(task.suite, task.shape, task.size, task.condition, task.suite_seed)
        rows = []
        for i, kind in enumerate(task.kinds):
            row = evaluate_kind(task, w, kind, first=(i == 0))
            if row is not None:
                rows.append(row)
        status, error = "ok", None
    except Exception as exc:  # one task's failure is recorded, the run goes on
        rows, status, error = [], "failed", f"{type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}"
    return {"key": task.key, "spec": task.spec(), "status": status, "error": error, "rows": rows,
            "seconds": round(time.perf_counter() - t0, 3)}


def _failed(task: Task, error: str) -> dict[str, Any]:
    return {"key": task.key, "spec": task.spec(), "status": "failed", "error": error, "rows": [], "seconds": 0.0}


@dataclass
class CalibrationResult:
    folder: Path
    tasks: int
    kept: int
    ran: int
    failed: list[dict[str, Any]]
    rows: list[dict[str, Any]] = field(default_factory=list)
    wall: float = 0.0
    backend: str = ""


def task_path(folder: Path, key: str) -> Path:
    return folder / "tasks" / f"{key}.json"


def _stored(folder: Path, task: Task) -> dict[str, Any] | None:
    try:
        with open(task_path(folder, task.key), encoding="utf-8") as fh:
            rec = json.load(fh)
    except (OSError, ValueError):
        return None
    if not isinstance(rec, dict) or rec.get("spec") != task.spec() or rec.get("status") != "ok":
        return None
    return rec


def _write_json(path: Path, doc: Any) -> None:
    from ...io.atomic import atomic_open

    with atomic_open(path, "w") as fh:
        json.dump(doc, fh)
        fh.write("\n")


def read_rows(folder: str | os.PathLike) -> list[dict[str, Any]]:
    """Every row of the stored tasks of a calibration run."""
    rows = []
    for p in sorted(Path(folder, "tasks").glob("*.json")):
        with open(p, encoding="utf-8") as fh:
            rows.extend(json.load(fh).get("rows", []))
    return rows


def run_calibration(out: str | os.PathLike, tasks: list[Task], backend: Any, *, force: bool = False,
                    progress: Callable[[int, int, str, str], None] | None = None, command: str = "",
                    machine: str = "") -> CalibrationResult:
    """Run (or resume) ``tasks`` into ``out`` on ``backend`` and write ``calibration.csv``,
    ``rows.csv`` and ``calibration.md`` there (:func:`.report.write_report`)."""
    from ...compare.backends import run_tasks
    from ...compare.run_marker import claim_run_folder
    from .calib_tables import write_report

    folder = claim_run_folder(out, "calibrate", force=force).path
    (folder / "tasks").mkdir(exist_ok=True)
    t0 = time.perf_counter()
    todo = [t for t in tasks if _stored(folder, t) is None]
    result = CalibrationResult(folder, len(tasks), len(tasks) - len(todo), 0, [], backend=backend.describe())
    done = [result.kept]

    def on_result(rec: dict[str, Any]) -> None:
        if rec["status"] == "ok":
            _write_json(task_path(folder, rec["key"]), rec)
            result.ran += 1
        else:
            result.failed.append(rec)
        done[0] += 1
        if progress is not None:
            progress(done[0], len(tasks), rec["key"], rec["status"])

    run_tasks(run_task, todo, backend, on_result, failed=_failed, key=lambda t: t.key)
    for task in tasks:
        rec = _stored(folder, task)
        if rec is not None:
            result.rows.extend(rec["rows"])
    result.wall = time.perf_counter() - t0
    write_report(folder, result.rows, command=command, machine=machine, wall=result.wall)
    return result
