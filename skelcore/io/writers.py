"""Writers, all atomic and never over a loaded input (:mod:`.atomic`): point sets as XYZ and NPY here
(PLY in :mod:`.ply`), and :func:`write_curve` / :func:`write_point_set`, which pick the writer by the
file's extension, with what each format cannot hold (:func:`curve_loss`, :func:`points_loss`)."""

from __future__ import annotations

import os
from pathlib import Path
from typing import Iterable

import numpy as np

from ..curve import CurveSkeleton
from .atomic import atomic_open

__all__ = ["write_points_xyz", "write_points_npy", "write_curve", "write_point_set", "curve_loss", "points_loss",
           "CURVE_SUFFIXES", "POINT_SUFFIXES"]

#: extensions :func:`write_curve` writes, and :func:`write_point_set`
CURVE_SUFFIXES = (".ply", ".obj", ".swc", ".cg", ".graphml", ".json")
POINT_SUFFIXES = (".ply", ".xyz", ".txt", ".npy")
_NO_RADIUS = {".obj": "OBJ", ".cg": ".cg"}


def write_points_xyz(
    path: str | os.PathLike, points: np.ndarray, *, inputs: Iterable[str | os.PathLike] = ()
) -> None:
    """``x y z`` per line, full double precision (round-trips exactly)."""
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must be N x 3, got shape {pts.shape}")
    with atomic_open(path, "w", inputs=inputs) as fh:
        np.savetxt(fh, pts, fmt="%.17g")


def write_points_npy(
    path: str | os.PathLike, points: np.ndarray, *, inputs: Iterable[str | os.PathLike] = ()
) -> None:
    """(N, 3) float64 ``.npy``."""
    pts = np.asarray(points, dtype=np.float64)
    if pts.ndim != 2 or pts.shape[1] != 3:
        raise ValueError(f"points must be N x 3, got shape {pts.shape}")
    with atomic_open(path, "wb", inputs=inputs) as fh:
        np.save(fh, pts, allow_pickle=False)


def _suffix(path: str | os.PathLike) -> str:
    return Path(path).suffix.lower()


def curve_loss(path: str | os.PathLike, curve: CurveSkeleton) -> str | None:
    """Why writing ``curve`` to ``path``'s format would lose something (a cycle in SWC, radii in OBJ,
    edges in a point format), or None when it keeps everything SkelScope reads back."""
    suffix = _suffix(path)
    if suffix in POINT_SUFFIXES and suffix not in CURVE_SUFFIXES:
        return f"{suffix} holds points only: the curve's {curve.n_edges} edges would be lost"
    if suffix == ".swc":
        from scipy.sparse import coo_matrix
        from scipy.sparse.csgraph import connected_components

        n = curve.n_vertices
        e = curve.edges
        comps = connected_components(coo_matrix((np.ones(len(e)), (e[:, 0], e[:, 1])), shape=(n, n)),
                                     directed=False)[0]
        cycles = curve.n_edges - n + comps
        if cycles:
            return f"SWC holds trees only: the curve has {cycles} independent cycle(s)"
    if suffix in _NO_RADIUS and curve.radius is not None:
        return f"{_NO_RADIUS[suffix]} has no vertex radius: the curve's radii would be lost"
    return None


def points_loss(path: str | os.PathLike) -> str | None:
    """Why a point set cannot go to ``path``'s format (curve-only formats), or None."""
    suffix = _suffix(path)
    if suffix in (".swc", ".cg"):
        return f"{suffix} holds curve skeletons only (a point set has no edges)"
    return None


def write_curve(
    path: str | os.PathLike, curve: CurveSkeleton, *, inputs: Iterable[str | os.PathLike] = (), binary: bool = True,
    lossy: bool = False,
) -> None:
    """Write ``curve`` in the format of ``path``'s extension (:data:`CURVE_SUFFIXES`; a point format
    gets the vertices only). Radii go to PLY (a double ``radius`` property), SWC, GraphML and JSON.
    ValueError for an extension no writer handles, or a cycle in SWC (unless ``lossy``: then SWC
    gets the breadth-first spanning forest)."""
    from .arrays import write_curve_json
    from .graph_xml import write_graphml
    from .ply import write_curve_ply
    from .swc import write_swc
    from .text import write_curve_cg, write_curve_obj

    suffix = _suffix(path)
    v, e, r = curve.vertices, curve.edges, curve.radius
    if suffix == ".ply":
        write_curve_ply(path, v, e, scalars={} if r is None else {"radius": r}, inputs=inputs, binary=binary)
    elif suffix == ".obj":
        write_curve_obj(path, v, e, inputs=inputs)
    elif suffix == ".cg":
        write_curve_cg(path, v, e, inputs=inputs)
    elif suffix == ".swc":
        write_swc(path, v, e, r, inputs=inputs, spanning=lossy)
    elif suffix == ".graphml":
        write_graphml(path, v, e, r, inputs=inputs)
    elif suffix == ".json":
        write_curve_json(path, v, e, r, inputs=inputs)
    elif suffix in POINT_SUFFIXES:
        write_point_set(path, v, inputs=inputs, binary=binary)
    else:
        raise ValueError(f"no curve writer for {suffix or '(no extension)'} (writable: {', '.join(CURVE_SUFFIXES)})")


def write_point_set(
    path: str | os.PathLike, points: np.ndarray, *, inputs: Iterable[str | os.PathLike] = (), binary: bool = True,
) -> None:
    """Write a point set in the format of ``path``'s extension: PLY, XYZ (``.xyz``/``.txt``), NPY, and
    also OBJ (``v`` lines), GraphML (nodes) and JSON (``{"points": ...}``)."""
    from .arrays import write_curve_json
    from .graph_xml import write_graphml
    from .ply import write_points_ply
    from .text import write_curve_obj

    suffix = _suffix(path)
    pts = np.asarray(points, dtype=np.float64)
    none = np.empty((0, 2), np.int64)
    if suffix == ".ply":
        write_points_ply(path, pts, inputs=inputs, binary=binary)
    elif suffix in (".xyz", ".txt"):
        write_points_xyz(path, pts, inputs=inputs)
    elif suffix == ".npy":
        write_points_npy(path, pts, inputs=inputs)
    elif suffix == ".obj":
        write_curve_obj(path, pts, none, inputs=inputs)
    elif suffix == ".graphml":
        write_graphml(path, pts, none, inputs=inputs)
    elif suffix == ".json":
        write_curve_json(path, pts, none, inputs=inputs)
    else:
        raise ValueError(f"no point-set writer for {suffix or '(no extension)'} "
                         f"(writable: {', '.join(POINT_SUFFIXES + ('.obj', '.graphml', '.json'))})")
