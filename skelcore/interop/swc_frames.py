"""Tables of SWC rows (a pandas DataFrame, a navis TreeNeuron's ``nodes``) as curves, and tables with
x, y, z columns as point sets. Columns are found by name, case-insensitively, under the names SWC
tools use (navis: node_id, parent_id; SWC files: id/n, parent/pid; radius/r)."""

from __future__ import annotations

import numpy as np

from ..errors import SkelInputError

__all__ = ["swc_columns", "xyz_columns", "frame_curve_parts", "frame_points"]

_ALIASES = {
    "id": ("node_id", "id", "n", "sample_number", "treenode_id"),
    "parent": ("parent_id", "parent", "pid", "parent_sample"),
    "radius": ("radius", "r", "radii"),
}


def _lower(columns) -> dict[str, object]:
    return {str(c).strip().lower(): c for c in columns}


def xyz_columns(columns) -> list | None:
    """The x, y, z column labels (any case), or None."""
    low = _lower(columns)
    return [low[k] for k in "xyz"] if all(k in low for k in "xyz") else None


def swc_columns(columns) -> dict[str, object] | None:
    """{"id", "parent", "x", "y", "z", and "radius" when present} -> column label, or None when a
    table has not the SWC columns (a node id, a parent id and x, y, z)."""
    low = _lower(columns)
    xyz = xyz_columns(columns)
    found = {role: next((low[a] for a in names if a in low), None) for role, names in _ALIASES.items()}
    if xyz is None or found["id"] is None or found["parent"] is None:
        return None
    out = {"id": found["id"], "parent": found["parent"], "x": xyz[0], "y": xyz[1], "z": xyz[2]}
    if found["radius"] is not None:
        out["radius"] = found["radius"]
    return out


def _column(frame, label, name: str, what: str) -> np.ndarray:
    try:
        return np.asarray(frame[label].to_numpy(), dtype=np.float64)
    except (TypeError, ValueError):
        raise SkelInputError(f"{name}: DataFrame column {label!r} ({what}) is not numbers") from None


def frame_curve_parts(frame, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(vertices, edges, radius) of a DataFrame of SWC rows (row order kept; a negative parent is a root)."""
    from ..io.swc import parent_edges

    cols = swc_columns(frame.columns)
    if cols is None:
        have = ", ".join(str(c) for c in list(frame.columns)[:10]) or "none"
        raise SkelInputError(
            f"{name}: DataFrame has no SWC columns (needs node_id/id, parent_id/parent, x, y, z; has {have})"
        )
    vertices = np.column_stack([_column(frame, cols[k], name, k) for k in "xyz"]) if len(frame) else np.empty((0, 3))
    ids = _column(frame, cols["id"], name, "node id")
    parents = np.nan_to_num(_column(frame, cols["parent"], name, "parent id"), nan=-1.0)  # navis: root parent NaN/-1
    edges = parent_edges(ids, parents, name)
    radius = _column(frame, cols["radius"], name, "radius") if "radius" in cols else None
    return vertices, edges, radius


def frame_points(frame, name: str) -> np.ndarray:
    """The x, y, z columns of a DataFrame (or all its columns when it has exactly three)."""
    cols = xyz_columns(frame.columns)
    if cols is None:
        if len(frame.columns) == 3:
            cols = list(frame.columns)
        else:
            have = ", ".join(str(c) for c in list(frame.columns)[:10]) or "none"
            raise SkelInputError(f"{name}: DataFrame has no x, y, z columns (has {have})")
    return np.column_stack([_column(frame, c, name, "coordinate") for c in cols]) if len(frame) else np.empty((0, 3))
