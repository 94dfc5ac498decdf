"""Reading a finished ``skelcore compare`` folder: its datasets, methods and conditions, and
one job's stored Evaluation, for the viewer's A/B view. Read only: nothing in the folder is written
(unlike :class:`.store.Store`, which sweeps and creates), and nothing is recomputed.

Every mistake (no such folder, not a run, unknown dataset / method / condition / seed, a job that
failed or never finished, a run stored before the skeletons were kept) is a one-line SkelInputError.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from ..errors import SkelInputError
from ..evaluation import Evaluation
from ..io.evaluation_files import evaluation_from_store

__all__ = ["CompareRun", "JobEntry", "open_run", "is_run_path"]


@dataclass(frozen=True)
class JobEntry:
    key: str
    shape: str
    method: str
    condition: str
    seed: int

    @property
    def label(self) -> str:
        return f"{self.shape} / {self.method} / {self.condition} / seed {self.seed}"


def is_run_path(path: str | os.PathLike) -> bool:
    """A compare folder, or its ``index.json`` (what the viewer accepts when dropped)."""
    p = Path(path)
    if p.is_dir():
        return (p / "index.json").is_file() and (p / "jobs").is_dir()
    return p.name == "index.json" and (p.parent / "jobs").is_dir()


def _choose(what: str, value: str | None, choices: list[str], where: Path) -> str:
    if value is None:
        if not choices:
            raise SkelInputError(f"the run has no {what}", where)
        return choices[0]
    if value not in choices:
        raise SkelInputError(f"unknown {what} {value!r}: the run has {', '.join(map(repr, choices)) or 'none'}", where)
    return value


class CompareRun:
    """The index of a compare folder and lookups into its ``jobs/``."""

    def __init__(self, root: Path, index: dict[str, Any]) -> None:
        self.root = root
        self.index = index
        try:
            self.jobs = [JobEntry(str(j["key"]), str(j["shape"]), str(j["method"]), str(j["condition"]), int(j["seed"]))
                         for j in index.get("jobs") or []]
        except (KeyError, TypeError, ValueError):
            raise SkelInputError("index.json: a job entry lacks key, shape, method, condition or seed", root) from None
        self.shapes = [str(s) for s in index.get("shapes") or []] or sorted({j.shape for j in self.jobs})
        self.methods = [str(m) for m in index.get("methods") or []] or sorted({j.method for j in self.jobs})
        self.conditions = [str(c) for c in index.get("conditions") or []] or sorted({j.condition for j in self.jobs})

    @property
    def name(self) -> str:
        return self.root.name

    def seeds(self, shape: str | None = None, condition: str | None = None) -> list[int]:
        return sorted({j.seed for j in self.jobs if shape in (None, j.shape) and condition in (None, j.condition)})

    def methods_for(self, shape: str, condition: str, seed: int | None = None) -> list[str]:
        """The methods with a job for this dataset and condition (a ``files`` method of clean clouds
        has none under a degrading condition), in the manifest's order."""
        have = {j.method for j in self.jobs if j.shape == shape and j.condition == condition
                and seed in (None, j.seed)}
        return [m for m in self.methods if m in have]

    def find(self, shape: str | None, method: str, condition: str | None = None, seed: int | None = None) -> JobEntry:
        shape = _choose("dataset", shape, self.shapes, self.root)
        method = _choose("method", method, self.methods, self.root)
        condition = _choose("condition", condition, self.conditions, self.root)
        seeds = self.seeds(shape, condition)
        if seed is not None and seed not in seeds:
            raise SkelInputError(f"unknown seed {seed} for {shape} / {condition}: the run has "
                                 f"{', '.join(map(str, seeds)) or 'none'}", self.root)
        for j in self.jobs:
            if (j.shape, j.method, j.condition) == (shape, method, condition) and (seed is None or j.seed == seed):
                return j
        raise SkelInputError(f"method {method!r} has no job for {shape} under condition {condition!r}", self.root)

    def record(self, job: JobEntry) -> dict[str, Any] | None:
        try:
            with open(self.root / "jobs" / f"{job.key}.json", encoding="utf-8") as fh:
                rec = json.load(fh)
        except (OSError, ValueError):
            return None
        return rec if isinstance(rec, dict) else None

    def status(self, job: JobEntry) -> tuple[str, str]:
        """("ok" | "failed" | "missing", the failure's one line)."""
        rec = self.record(job)
        if rec is None:
            return "missing", "not finished (no record)"
        return str(rec.get("status", "failed")), str(rec.get("error", ""))

    def scores(self, job: JobEntry) -> dict[str, Any]:
        return dict((self.record(job) or {}).get("scores") or {})

    def arrays_size(self, job: JobEntry) -> int:
        """Bytes of the job's stored arrays (0 when there are none)."""
        try:
            return (self.root / "jobs" / f"{job.key}.npz").stat().st_size
        except OSError:
            return 0

    def evaluation(self, job: JobEntry) -> Evaluation:
        """The job's stored Evaluation (nothing recomputed)."""
        rec = self.record(job)
        where = self.root / "jobs" / f"{job.key}.json"
        if rec is None:
            raise SkelInputError(f"job {job.label} has not finished (no record)", where)
        if rec.get("status") != "ok" or not isinstance(rec.get("evaluation"), dict):
            raise SkelInputError(f"job {job.label} failed: {rec.get('error') or 'no evaluation stored'}", where)
        npz = self.root / "jobs" / f"{job.key}.npz"
        try:
            with np.load(npz) as z:
                arrays = {k: z[k] for k in z.files}
        except FileNotFoundError:
            raise SkelInputError(f"job {job.label}: its arrays are missing", npz) from None
        except (OSError, ValueError) as exc:
            raise SkelInputError(f"job {job.label}: cannot read its arrays ({exc})", npz) from None
        return evaluation_from_store(rec["evaluation"], arrays, where=str(self.root))


def open_run(path: str | os.PathLike) -> CompareRun:
    """A compare output folder (or its ``index.json``), checked to be one."""
    p = Path(path)
    if p.name == "index.json" and p.is_file():
        p = p.parent
    if not p.exists():
        raise SkelInputError("no such folder", p)
    if not p.is_dir():
        raise SkelInputError("not a compare output folder (give the folder or its index.json)", p)
    index_path = p / "index.json"
    try:
        with open(index_path, encoding="utf-8") as fh:
            index = json.load(fh)
    except FileNotFoundError:
        raise SkelInputError("not a compare output folder (no index.json)", p) from None
    except (OSError, ValueError) as exc:
        raise SkelInputError(f"cannot read index.json: {exc}", p) from None
    if not isinstance(index, dict):
        raise SkelInputError("index.json is not a compare index", p)
    return CompareRun(p, index)
