"""Resumable benchmark runs of many independent tasks (the validity study, the warnings'
calibration): each task's record (its spec, status, rows and seconds) is stored as
``tasks/{key}.json`` once done and kept by a rerun while its spec is unchanged; the tasks run on the
pool or Dask cluster of ``skelcore compare`` (docs/validity.md, docs/diagnostics.md)."""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Callable

__all__ = ["TaskRun", "task_record", "failed_record", "task_path", "stored", "read_rows", "run_stored_tasks"]


@dataclass
class TaskRun:
    """What a run did: its folder, the tasks asked, kept from an earlier run, run now and failed (their
    records), every stored row, the wall seconds and the backend's description; and the statistics tables
    its report was written from, by set, where the run writes them (the validity study)."""

    folder: Path
    tasks: int
    kept: int
    ran: int
    failed: list[dict[str, Any]]
    rows: list[dict[str, Any]] = field(default_factory=list)
    wall: float = 0.0
    backend: str = ""
    tables: dict[str, list[dict[str, Any]]] = field(default_factory=dict)


def task_record(task: Any, rows_of: Callable[[Any], list[dict[str, Any]]]) -> dict[str, Any]:
    """``task``'s record (runs in a worker): ``rows_of(task)`` with its seconds; an error is one line."""
    t0 = time.perf_counter()
    try:
        rows = rows_of(task)
        status, error = "ok", None
    except Exception as exc:  # one task's failure is recorded, the run goes on
        rows, status, error = [], "failed", f"{type(exc).__name__}: {str(exc).splitlines()[0] if str(exc) else ''}"
    return {"key": task.key, "spec": task.spec(), "status": status, "error": error, "rows": rows,
            "seconds": round(time.perf_counter() - t0, 3)}


def failed_record(task: Any, error: str) -> dict[str, Any]:
    """The record of a task the backend could not run."""
    return {"key": task.key, "spec": task.spec(), "status": "failed", "error": error, "rows": [], "seconds": 0.0}


def task_path(folder: Path, key: str) -> Path:
    return Path(folder) / "tasks" / f"{key}.json"


def stored(folder: Path, task: Any) -> dict[str, Any] | None:
    """The task's stored record when it holds the same spec and succeeded, else None."""
    try:
        with open(task_path(folder, task.key), encoding="utf-8") as fh:
            rec = json.load(fh)
    except (OSError, ValueError):
        return None
    if not isinstance(rec, dict) or rec.get("spec") != task.spec() or rec.get("status") != "ok":
        return None
    return rec


def _write_json(path: Path, doc: Any) -> None:
    from ..io.atomic import atomic_open

    with atomic_open(path, "w") as fh:
        json.dump(doc, fh, indent=None, allow_nan=True)
        fh.write("\n")


def read_rows(folder: str | os.PathLike) -> list[dict[str, Any]]:
    """Every row of a run's stored tasks."""
    rows = []
    for p in sorted(Path(folder, "tasks").glob("*.json")):
        with open(p, encoding="utf-8") as fh:
            rows.extend(json.load(fh).get("rows", []))
    return rows


def run_stored_tasks(folder: Path, tasks: list, run_task: Callable[[Any], dict[str, Any]], backend: Any,
                     progress: Callable[[int, int, str, str], None] | None = None) -> TaskRun:
    """Run the ``tasks`` without a stored record on ``backend`` (:func:`skelcore.compare.backends.run_tasks`),
    store each success as it lands, and gather every stored row; ``progress(done, total, key, status)``."""
    from ..compare.backends import run_tasks

    (Path(folder) / "tasks").mkdir(exist_ok=True)
    t0 = time.perf_counter()
    todo = [t for t in tasks if stored(folder, t) is None]
    result = TaskRun(Path(folder), len(tasks), len(tasks) - len(todo), 0, [], backend=backend.describe())
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

    run_tasks(run_task, todo, backend, on_result, failed=failed_record, key=lambda t: t.key)
    for task in tasks:
        rec = stored(folder, task)
        if rec is not None:
            result.rows.extend(rec["rows"])
    result.wall = time.perf_counter() - t0
    return result
