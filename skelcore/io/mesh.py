"""Triangle meshes: an OBJ's ``v`` and ``f`` lines (the cloud readers of :mod:`.text` drop faces).

The benchmark's real suite samples the surface of a neuron's mesh (docs/benchmark.md, "The real
suite"), so it needs the faces; polygons are fanned into triangles. Every problem is a one-line
:class:`~skelcore.errors.SkelInputError` naming the file.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..errors import SkelInputError
from ._common import decode_text
from .text import _obj_index

__all__ = ["TriangleMesh", "read_obj_mesh"]


@dataclass(frozen=True)
class TriangleMesh:
    """Vertices (V x 3, float64, the file's units) and triangles (F x 3, int64 rows of vertex indices)."""

    vertices: np.ndarray
    faces: np.ndarray

    def boundary_edges(self) -> int:
        """Edges used by exactly one triangle (0 for a closed surface)."""
        e = np.sort(self.faces[:, [0, 1, 1, 2, 2, 0]].reshape(-1, 2), axis=1)
        _, counts = np.unique(e, axis=0, return_counts=True)
        return int(np.sum(counts == 1))

    def triangles(self) -> np.ndarray:
        """The corners, F x 3 x 3."""
        return self.vertices[self.faces]


def read_obj_mesh(path: str | os.PathLike) -> TriangleMesh:
    """The ``v`` and ``f`` lines of an OBJ (``f a/b/c`` tokens and negative indices allowed, polygons
    fanned from their first corner); a file without faces, a bad number or index is an error."""
    path = Path(path)
    try:
        data = path.read_bytes()
    except OSError as exc:
        raise SkelInputError(f"cannot read the mesh: {exc.strerror or exc}", path) from None
    verts: list[list[str]] = []
    faces: list[tuple[int, int, int]] = []
    face_lines: list[int] = []
    for lineno, line in enumerate(decode_text(data).splitlines(), 1):
        parts = line.split()
        if not parts:
            continue
        if parts[0] == "v":
            if len(parts) < 4:
                raise SkelInputError(f"line {lineno}: vertex line has {len(parts) - 1} values, expected 3", path)
            verts.append(parts[1:4])
        elif parts[0] == "f":
            if len(parts) < 4:
                raise SkelInputError(f"line {lineno}: face with {len(parts) - 1} corners, expected at least 3", path)
            idx = [_obj_index(t, len(verts), lineno, path) for t in parts[1:]]
            for k in range(1, len(idx) - 1):
                faces.append((idx[0], idx[k], idx[k + 1]))
                face_lines.append(lineno)
    if not faces:
        raise SkelInputError("no faces (f lines): not a surface mesh", path)
    try:
        vertices = np.array(verts, dtype=np.float64).reshape(-1, 3)
    except ValueError:
        raise SkelInputError("vertex coordinates are not all numbers", path) from None
    if not np.all(np.isfinite(vertices)):
        raise SkelInputError("vertex coordinates must be finite", path)
    f = np.array(faces, dtype=np.int64)
    bad = np.flatnonzero((f < 0).any(axis=1) | (f >= len(vertices)).any(axis=1))
    if bad.size:
        raise SkelInputError(f"line {face_lines[bad[0]]}: face corner out of range (file has {len(vertices)} "
                             "vertices)", path)
    return TriangleMesh(vertices, f)
