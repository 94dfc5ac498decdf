"""``run_compare``: manifest -> jobs -> store -> ``results.csv``, ``leaderboard.*`` (and
``leaderboard_sound.*``, over the cases where every method is sound), ``report.html``.

Claims DIR first (:mod:`.run_marker`: a new or empty folder, or one of our runs; never a user's
folder unless forced). Also writes ``DIR/index.json`` (the jobs in manifest order and the run's
settings) so that ``skelcore figure DIR`` and a later report need no manifest. Everything is rebuilt from the store,
so the tables of a rerun (or of a run killed and resumed) are those of one uninterrupted run.
"""

from __future__ import annotations

import json
import os
from dataclasses import dataclass
from typing import Any, Callable

from ..io.atomic import atomic_open
from .jobs import Job, make_jobs
from .leaderboard import Leaderboard, build_leaderboard, build_sound_leaderboard
from .manifest import Manifest, load_manifest
from .profiles import Profile, load_profiles
from .results_csv import collect_rows, write_results_csv
from .backends import Backend, RunSummary, run_jobs
from .job_store import Store
from .run_marker import claim_run_folder

__all__ = ["CompareResult", "run_compare", "write_outputs", "load_index"]


@dataclass
class CompareResult:
    """What :func:`run_compare` returns: the checked manifest, every job with its record, the run's
    counts, the results.csv rows, the leaderboard and the paths of the files written (docs/compare.md)."""

    manifest: Manifest
    jobs: list[Job]
    summary: RunSummary
    rows: list[dict[str, Any]]
    leaderboard: Leaderboard
    files: dict[str, str]


def run_compare(manifest_path: str | os.PathLike, out_dir: str | os.PathLike, backend: Backend = Backend("serial"),
                *, profiles_path: str | os.PathLike | None = None, report: bool = True, quiet: bool = True,
                retry_failed: bool = False, on_record: Callable[[dict[str, Any]], None] | None = None,
                force: bool = False) -> CompareResult:
    """Validate everything first (manifest, profiles, output folder), then run the missing jobs.

    ``out_dir`` must be new, empty or one of our compare runs (its ``.skelscope-run`` marker,
    :mod:`.run_marker`); any other folder is refused with a one-line SkelInputError unless
    ``force`` (the CLI's ``--force``), so a user's own ``results.csv`` is never replaced unasked.
    """
    manifest = load_manifest(manifest_path)
    profiles = load_profiles(profiles_path)
    inputs = tuple(s.path for s in manifest.shapes) + tuple(s.reference for s in manifest.shapes if s.reference) + (
        manifest.path,)  # never written over
    jobs = make_jobs(manifest)
    claim_run_folder(out_dir, "compare", force=force, manifest=manifest.path, inputs=inputs)
    store = Store(out_dir, inputs=inputs)
    _write_index(out_dir, manifest, jobs, backend, inputs)
    summary = run_jobs(jobs, store, backend, quiet=quiet, retry_failed=retry_failed, on_record=on_record)
    rows, board, files = write_outputs(out_dir, manifest, jobs, store, profiles, report=report, inputs=inputs,
                                       meta={"backend": summary.backend, "manifest": manifest.path})
    return CompareResult(manifest, jobs, summary, rows, board, files)


def write_outputs(out_dir: str | os.PathLike, manifest: Manifest, jobs: list[Job], store: Store,
                  profiles: tuple[Profile, ...], *, report: bool = True, inputs: tuple[str, ...] = (),
                  meta: dict[str, Any] | None = None) -> tuple[list[dict[str, Any]], Leaderboard, dict[str, str]]:
    out_dir = os.fspath(out_dir)
    rows = collect_rows(jobs, store, profiles)
    files = {"results": os.path.join(out_dir, "results.csv")}
    write_results_csv(files["results"], rows, profiles, inputs=inputs)
    methods = [m.name for m in manifest.methods]
    conditions = [c.name for c in manifest.conditions]
    board = build_leaderboard(rows, profiles, methods, conditions)
    board.sound = build_sound_leaderboard(rows, profiles, methods, conditions)
    files.update({f"leaderboard.{k}": v for k, v in board.write(out_dir, inputs=inputs).items()})
    if report:
        from .report import write_report

        files["report"] = write_report(out_dir, rows, board, store, shapes=[s.name for s in manifest.shapes],
                                       methods=methods, conditions=conditions, meta=meta, inputs=inputs,
                                       title=f"skelcore compare: {os.path.basename(manifest.path)}")
    return rows, board, files


def _write_index(out_dir, manifest: Manifest, jobs: list[Job], backend: Backend, inputs) -> None:
    doc = {"manifest": manifest.path, "backend": backend.describe(),
           "shapes": [s.name for s in manifest.shapes], "methods": [m.name for m in manifest.methods],
           "conditions": [c.name for c in manifest.conditions], "seeds": list(manifest.seeds),
           "jobs": [{"key": j.key, "shape": j.shape.name, "method": j.method.name, "condition": j.condition.name,
                     "seed": j.seed} for j in jobs]}
    with atomic_open(os.path.join(os.fspath(out_dir), "index.json"), "w", inputs=inputs) as fh:
        json.dump(doc, fh, indent=1)
        fh.write("\n")


def load_index(out_dir: str | os.PathLike) -> dict[str, Any]:
    from ..errors import SkelInputError

    path = os.path.join(os.fspath(out_dir), "index.json")
    try:
        with open(path, encoding="utf-8") as fh:
            return json.load(fh)
    except FileNotFoundError:
        raise SkelInputError("not a compare output folder (no index.json)", out_dir) from None
    except (OSError, ValueError) as exc:
        raise SkelInputError(f"cannot read index.json: {exc}", out_dir) from None
