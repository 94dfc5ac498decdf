"""The edit log: a JSON document naming the curve it starts from (:func:`content_hash`) and the
operations in order, so an edit session can be replayed, reviewed and shared (docs/output_formats.md
"The edit log"). :func:`replay` refuses, in one line, a log made for another curve, an unknown
operation or argument, and an id out of range."""

from __future__ import annotations

import json
import os
from typing import Any, Callable, Iterable

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from ..io.atomic import atomic_open
from ..io.schemas import SCHEMA_VERSION
from .branch_ops import delete_branch, prune_branch
from .change import Change, content_hash
from .edge_ops import add_edge, cut_cycle, delete_edge, split_edge
from .vertex_ops import add_vertex, delete_vertex, merge_vertices, move_vertex

__all__ = ["FORMAT", "OPERATIONS", "new_log", "apply", "replay", "write_log", "read_log"]

FORMAT = "skelscope-edit-log"


def _add_vertex(curve: CurveSkeleton, position: Any, attach_to: Any = None, radius: Any = None):
    return add_vertex(curve, position, attach_to, radius)


def _move_vertex(curve: CurveSkeleton, vertex: Any, position: Any):
    return move_vertex(curve, vertex, position)


#: operation name -> (function, required arguments, optional arguments), as the log spells them
OPERATIONS: dict[str, tuple[Callable[..., tuple[CurveSkeleton, Change]], tuple[str, ...], tuple[str, ...]]] = {
    "delete_vertex": (delete_vertex, ("vertex",), ()),
    "delete_edge": (delete_edge, ("edge",), ()),
    "delete_branch": (delete_branch, ("branch",), ()),
    "prune_branch": (prune_branch, ("branch",), ()),
    "add_vertex": (_add_vertex, ("position",), ("attach_to", "radius")),
    "add_edge": (add_edge, ("edge",), ()),
    "split_edge": (split_edge, ("edge",), ("t",)),
    "merge_vertices": (merge_vertices, ("keep", "remove"), ()),
    "move_vertex": (_move_vertex, ("vertex", "position"), ()),
    "cut_cycle": (cut_cycle, ("edge",), ()),
}


def new_log(curve: CurveSkeleton, changes: Iterable[Change | dict] = ()) -> dict[str, Any]:
    """The log of ``changes`` (Change records or ``{"op", "args"}`` entries) made from ``curve``."""
    ops = [c.to_dict() if isinstance(c, Change) else {"op": c["op"], "args": dict(c.get("args", {}))}
           for c in changes]
    return {"format": FORMAT, "schema_version": SCHEMA_VERSION, "skeleton_hash": content_hash(curve),
            "operations": ops}


def apply(curve: CurveSkeleton, entry: dict[str, Any], where: str = "operation") -> tuple[CurveSkeleton, Change]:
    """One log entry ``{"op": name, "args": {...}}`` applied to ``curve``."""
    if not isinstance(entry, dict) or not isinstance(entry.get("op"), str):
        raise SkelInputError(f"{where}: an operation is {{\"op\": name, \"args\": {{...}}}}, got {entry!r}")
    op = entry["op"]
    if op not in OPERATIONS:
        raise SkelInputError(f"{where}: unknown operation {op!r} (known: {', '.join(OPERATIONS)})")
    fn, required, optional = OPERATIONS[op]
    args = entry.get("args", {})
    if not isinstance(args, dict):
        raise SkelInputError(f"{where}: {op} args must be an object, got {args!r}")
    unknown = sorted(set(args) - set(required) - set(optional))
    missing = [a for a in required if a not in args]
    if unknown or missing:
        raise SkelInputError(f"{where}: {op} takes {', '.join(required + optional)}"
                             + (f"; unknown {', '.join(unknown)}" if unknown else "")
                             + (f"; missing {', '.join(missing)}" if missing else ""))
    try:
        return fn(curve, **args)
    except SkelInputError as exc:
        raise SkelInputError(f"{where} ({op}): {exc}") from None


def replay(curve: CurveSkeleton, log: dict[str, Any]) -> tuple[CurveSkeleton, list[Change]]:
    """Apply the log's operations in order to ``curve``, which must be the curve the log was made for
    (its content hash); returns the edited curve and every Change."""
    _check_document(log)
    if log["skeleton_hash"] != content_hash(curve):
        raise SkelInputError("the edit log was made for another skeleton (its skeleton_hash is not this curve's)")
    changes = []
    for i, entry in enumerate(log["operations"]):
        curve, change = apply(curve, entry, f"operation {i}")
        changes.append(change)
    return curve, changes


def _check_document(log: object) -> None:
    if not isinstance(log, dict) or log.get("format") != FORMAT:
        raise SkelInputError(f"not an edit log (no \"format\": \"{FORMAT}\")")
    version = str(log.get("schema_version", ""))
    if version.split(".")[0] != SCHEMA_VERSION.split(".")[0]:
        raise SkelInputError(f"edit log version {version or '(none)'} is not readable here (reads {SCHEMA_VERSION})")
    if not isinstance(log.get("skeleton_hash"), str) or not isinstance(log.get("operations"), list):
        raise SkelInputError("an edit log needs skeleton_hash (a string) and operations (a list)")


def write_log(path: str | os.PathLike, log: dict[str, Any], inputs: Iterable[str | os.PathLike] = ()) -> None:
    """Write ``log`` as JSON, atomically (never over ``inputs``)."""
    _check_document(log)
    with atomic_open(path, "w", inputs) as fh:
        json.dump(log, fh, indent=1)
        fh.write("\n")


def read_log(path: str | os.PathLike) -> dict[str, Any]:
    """Read and check an edit log (one-line SkelInputError when it is not one)."""
    try:
        with open(path, encoding="utf-8") as fh:
            log = json.load(fh)
    except OSError as exc:
        raise SkelInputError(f"cannot read ({exc.strerror or exc})", path) from None
    except (json.JSONDecodeError, UnicodeDecodeError) as exc:
        raise SkelInputError(f"not JSON ({exc})", path) from None
    try:
        _check_document(log)
    except SkelInputError as exc:
        raise SkelInputError(str(exc), path) from None
    return log
