"""Which folders are our runs: a ``.skelscope-run`` marker, written when a run's folder is claimed,
so that a command never writes into a user's folder.

``skelcore compare --out DIR`` (and the ``bench`` commands, with their own ``kind``) call
:func:`claim_run_folder` once, after checking their inputs and before writing anything:

- DIR does not exist, or is an empty folder: it becomes a run (the marker is written);
- DIR holds our marker of the same kind (and the same ``details``, when the caller gives them: a
  benchmark's suite, seed and generator): the run is resumed (the marker is left as it was);
- anything else (a user's folder with a ``results.csv`` and notes, another kind of run, a run made
  by a skelcore older than the marker, an unreadable marker): refused with one line, unless
  ``force``, which writes the marker so that later runs resume without it.

A run is recognised by the marker only, never by its file names: a folder that merely holds an
``index.json`` and a ``jobs/`` may be anyone's. The marker is JSON: ``skelscope_run`` (format
version), ``kind``, ``skelcore`` (the version that created it), ``manifest``, ``created`` (UTC) and the caller's
``details``.
"""

from __future__ import annotations

import json
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Iterable

from ..errors import SkelInputError
from ..io.atomic import atomic_open
from ..version import __version__

__all__ = ["MARKER", "MARKER_FORMAT", "RunClaim", "read_marker", "is_run_folder", "claim_run_folder"]

MARKER = ".skelscope-run"
MARKER_FORMAT = 1
#: the marker ``skelcore bench make`` wrote before it used this one
LEGACY_BENCH_MARKER = ".skelscope-bench"


@dataclass(frozen=True)
class RunClaim:
    """What :func:`claim_run_folder` found: ``state`` is "created" (new or empty folder), "resumed"
    (our marker was there) or "forced" (written into a folder that was not a run, or a run of other
    ``details``, with ``force``); ``previous``: the marker of this kind that was there, else None."""

    path: Path
    state: str
    marker: dict[str, Any]
    previous: dict[str, Any] | None = None


def read_marker(folder: str | os.PathLike) -> dict[str, Any] | None:
    """The folder's marker, or None when it has none or it is not ours (unreadable, not our JSON)."""
    try:
        with open(Path(folder) / MARKER, encoding="utf-8") as fh:
            doc = json.load(fh)
    except (OSError, ValueError):
        return None
    if not isinstance(doc, dict) or not isinstance(doc.get("skelscope_run"), int):
        return None
    return doc


def is_run_folder(folder: str | os.PathLike, kind: str | None = None) -> bool:
    """True when ``folder`` carries our marker (of ``kind``, when given)."""
    doc = read_marker(folder)
    return doc is not None and (kind is None or doc.get("kind") == kind)


def _write_marker(folder: Path, kind: str, manifest: str | os.PathLike | None, inputs: Iterable[str],
                  details: dict[str, Any] | None = None) -> dict[str, Any]:
    doc = {"skelscope_run": MARKER_FORMAT, "kind": kind, "skelcore": __version__,
           "manifest": None if manifest is None else os.path.abspath(os.fspath(manifest)),
           "created": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()), **(details or {})}
    with atomic_open(folder / MARKER, "w", inputs=tuple(inputs)) as fh:
        json.dump(doc, fh, indent=1)
        fh.write("\n")
    return doc


def _refusal(folder: Path, kind: str, entries: list[str]) -> str:
    """One line: why ``folder`` is not a run of ``kind``, and what to do."""
    where = "a new --out" if kind == "compare" else "a new folder"
    replace = f"choose {where}, or pass --force to write into it (files of the same names are replaced)"
    if (folder / MARKER).exists():
        doc = read_marker(folder)
        if doc is None:
            return f"has an unreadable {MARKER} marker: {replace}"
        return f"is a skelcore {doc.get('kind')!r} run, not a {kind} run: {replace}"
    if kind == "compare" and "index.json" in entries and "jobs" in entries:
        return (f"looks like a {kind} run made before skelcore marked its runs (no {MARKER}): if it is "
                "yours, pass --force once to resume it")
    if kind == "bench" and LEGACY_BENCH_MARKER in entries:
        return (f"looks like a benchmark made before skelcore marked its runs with {MARKER}: if it is yours, "
                "pass --force once to remake it")
    shown = ", ".join(repr(e) for e in sorted(entries)[:3]) + (", ..." if len(entries) > 3 else "")
    return f"exists and is not a skelcore {kind} run (no {MARKER} marker; it holds {shown}): {replace}"


def _describe(details: dict[str, Any]) -> str:
    return ", ".join(f"{k} {v!r}" for k, v in details.items())


def claim_run_folder(folder: str | os.PathLike, kind: str, *, force: bool = False,
                     manifest: str | os.PathLike | None = None, inputs: Iterable[str] = (),
                     details: dict[str, Any] | None = None) -> RunClaim:
    """Make ``folder`` a run of ``kind`` or resume it; a one-line SkelInputError (naming the folder)
    when it is someone else's, or our run of ``kind`` with other ``details`` (kept in the marker), and
    ``force`` is False. Call it before writing anything there."""
    p = Path(folder)
    if p.exists() and not p.is_dir():
        raise SkelInputError("output folder exists and is a file, not a folder", p)
    if not p.exists():
        try:
            p.mkdir(parents=True)
        except OSError as exc:
            raise SkelInputError(f"cannot create the output folder: {exc.strerror or exc}", p) from None
        entries: list[str] = []
    else:
        try:
            entries = os.listdir(p)
        except OSError as exc:
            raise SkelInputError(f"cannot read the output folder: {exc.strerror or exc}", p) from None
    previous = None
    if not entries:
        state = "created"
    else:
        doc = read_marker(p)
        if doc is not None and doc.get("kind") == kind:
            previous = doc
            found = {k: doc.get(k) for k in (details or {})}
            if found == dict(details or {}):
                return RunClaim(p, "resumed", doc, doc)
            if not force:
                raise SkelInputError(f"holds a {kind} run of {_describe(found)}, not of {_describe(details or {})}: "
                                     "choose a new folder, or pass --force to remake it", p)
        elif not force:
            raise SkelInputError(_refusal(p, kind, entries), p)
        state = "forced"
    if not os.access(p, os.W_OK | os.X_OK):
        raise SkelInputError("output folder is not writable", p)
    return RunClaim(p, state, _write_marker(p, kind, manifest, inputs, details), previous)
