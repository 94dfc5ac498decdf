"""Format detection and the loaders: ``load_cloud``, ``load_points``, ``load_curve``, ``load_any``.

The format is detected from the file's content first and from its extension otherwise; every loader
returns float64 coordinates in the file's units (docs/metrics.md 0), protects the path from writers and turns
any problem into a one-line :class:`~skelcore.errors.SkelInputError` naming the file. Each loader also
takes another library's object instead of a path (:mod:`skelcore.interop`) and checks it the same way.
"""


from __future__ import annotations

import os
import warnings
from dataclasses import dataclass
from pathlib import Path
from typing import Callable

import numpy as np

from ..curve import CurveSkeleton
from ..errors import SkelInputError
from . import atomic
from ._common import RawData, decode_text, is_comment
from .arrays import read_json, read_npy, read_npz
from .graph_xml import is_gexf, is_graphml, read_gexf, read_graphml
from .las import is_las, read_las
from .pcd import is_pcd, read_pcd
from .swc import read_swc
from .treeqsm import is_mat, read_treeqsm
from .ply import is_ply, read_ply
from .text import (
    is_cg,
    is_off,
    looks_like_graph,
    looks_like_obj,
    looks_like_polylines,
    read_cg,
    read_graph,
    read_obj,
    read_off,
    read_polylines,
    read_xyz,
)

__all__ = ["Loaded", "load_any", "load_cloud", "load_points", "load_curve", "detect_format", "SUPPORTED_EXTENSIONS"]

_READERS: dict[str, Callable[[Path, bytes], RawData]] = {
    "ply": read_ply,
    "pcd": read_pcd,
    "xyz": read_xyz,
    "obj": read_obj,
    "off": read_off,
    "cg": read_cg,
    "swc": read_swc,
    "polylines": read_polylines,
    "npy": read_npy,
    "npz": read_npz,
    "json": read_json,
    "graph": read_graph,
    "las": read_las,
    "graphml": read_graphml,
    "gexf": read_gexf,
    "mat": read_treeqsm,
}

_BY_SUFFIX = {
    ".ply": "ply",
    ".pcd": "pcd",
    ".xyz": "xyz",
    ".txt": "xyz",
    ".csv": "xyz",
    ".pts": "xyz",
    ".asc": "xyz",
    ".xyzn": "xyz",
    ".xyzrgb": "xyz",
    ".xyzr": "xyz",  # Point2Skeleton's x y z radius list
    ".obj": "obj",
    ".off": "off",
    ".cg": "cg",
    ".swc": "swc",
    ".npy": "npy",
    ".npz": "npz",
    ".json": "json",
    ".graph": "graph",
    ".las": "las",
    ".laz": "las",
    ".graphml": "graphml",
    ".gexf": "gexf",
    ".mat": "mat",
}

#: For file dialogs: every extension the loaders accept (``.polylines.txt`` is a ``.txt``).
SUPPORTED_EXTENSIONS: tuple[str, ...] = tuple(_BY_SUFFIX)

_HEAD_BYTES = 8192


@dataclass(frozen=True)
class Loaded:
    """What :func:`load_any` found: ``kind`` is ``"curve"`` for a file with edges (then ``curve`` is
    set) and ``"points"`` otherwise (then ``points`` is set)."""

    kind: str
    path: str
    format: str
    points: np.ndarray | None = None
    curve: CurveSkeleton | None = None


def detect_format(path: str | os.PathLike, head: bytes) -> str:
    """Format key for a file from its first bytes and its name (content wins over the extension)."""
    p = Path(path)
    if is_ply(head):
        return "ply"
    if head.startswith(b"\x93NUMPY"):
        return "npy"
    if head.startswith((b"PK\x03\x04", b"PK\x05\x06")):
        return "npz"
    if is_las(head):
        return "las"
    if is_mat(head):
        return "mat"
    text = decode_text(head).lstrip()
    if text.startswith("<"):
        if is_graphml(text):
            return "graphml"
        if is_gexf(text):
            return "gexf"
    if text.startswith(("{", "[")):
        return "json"
    if is_cg(text):
        return "cg"
    if is_pcd(text):
        return "pcd"
    first = next((ln.split() for ln in text.splitlines() if ln.strip() and not is_comment(ln.strip())), [])
    if first and is_off(first[0]):
        return "off"
    name = p.name.lower()
    if name.endswith(".polylines.txt"):
        return "polylines"
    fmt = _BY_SUFFIX.get(p.suffix.lower())
    if fmt == "xyz" or fmt is None:
        # Text tables and unknown extensions: recognise OBJ and CGAL polylines by content.
        if looks_like_obj(text):
            return "obj"
        if looks_like_polylines(text):
            return "polylines"
        if looks_like_graph(text):
            return "graph"
    if fmt is None:
        supported = ", ".join(sorted(set(SUPPORTED_EXTENSIONS)))
        raise SkelInputError(f"unknown file format {p.suffix or '(no extension)'!r} (supported: {supported})", p)
    return fmt


def _short(exc: BaseException) -> str:
    text = " ".join(str(exc).split()) or type(exc).__name__
    return text if len(text) <= 160 else text[:157] + "..."


def _read_raw(path: str | os.PathLike) -> RawData:
    """Existence and permission checks, format detection, parsing; only SkelInputError escapes."""
    try:
        p = Path(path)
    except TypeError:
        raise SkelInputError(f"not a file path: {path!r}") from None
    if not p.exists():
        raise SkelInputError("file not found", p)
    if p.is_dir():
        raise SkelInputError("is a folder, not a file", p)
    atomic.protect(p)
    try:
        data = p.read_bytes()
    except PermissionError:
        raise SkelInputError("permission denied", p) from None
    except OSError as exc:
        raise SkelInputError(f"cannot read file ({exc.strerror or _short(exc)})", p) from None
    if len(data) == 0 or (len(data) <= 4096 and not data.strip()):
        raise SkelInputError("file is empty", p)
    fmt = detect_format(p, data[:_HEAD_BYTES])
    try:
        raw = _READERS[fmt](p, data)
    except SkelInputError:
        raise
    except MemoryError:
        raise SkelInputError(f"too large to load as {fmt.upper()} (out of memory)", p) from None
    except Exception as exc:  # any parser failure is bad input, reported in one line
        raise SkelInputError(f"malformed {fmt.upper()} file: {_short(exc)}", p) from None
    if raw.vertices.ndim != 2 or raw.vertices.shape[1] != 3:
        raise SkelInputError(f"expected x y z rows, got shape {raw.vertices.shape}", p)
    return raw


def _point_set(raw: RawData, path: str | os.PathLike, what: str) -> np.ndarray:
    """Inputs must be usable (docs/metrics.md 0): at least one point, all finite, not all at one position."""
    v = np.ascontiguousarray(raw.vertices, dtype=np.float64)
    if len(v) == 0:
        raise SkelInputError(f"{what} is empty (0 points)", path)
    finite = np.isfinite(v).all(axis=1)
    if not finite.all():
        bad = np.flatnonzero(~finite)
        kind = "NaN" if np.isnan(v[bad[0]]).any() else "infinite"
        raise SkelInputError(
            f"{len(bad)} of {len(v)} points have NaN or infinite coordinates (first: row {bad[0]}, {kind})", path
        )
    if len(v) == 1:
        raise SkelInputError(f"{what} has a single point", path)
    if np.all(v == v[0]):
        raise SkelInputError(f"all {len(v)} points of the {what} are at the same position", path)
    return v


def _is_path(path: object) -> bool:
    return isinstance(path, (str, bytes, os.PathLike))


def _object_raw(obj: object, what: str) -> RawData:
    """A library object's points as RawData (:func:`skelcore.interop.points_of`)."""
    from ..interop.objects_in import points_of

    points = points_of(obj, what)  # an unknown object: a TypeError naming what is accepted
    try:
        v = np.asarray(points, dtype=np.float64)
    except (TypeError, ValueError):
        raise SkelInputError(f"{what}: coordinates are not numbers") from None
    if v.ndim != 2 or v.shape[1] != 3:
        raise SkelInputError(f"{what}: expected an N x 3 array of points, got shape {v.shape}")
    return RawData(vertices=v, edges=None, format=type(obj).__name__)


def load_cloud(path: str | os.PathLike | object) -> np.ndarray:
    """The original cloud P_o as an (N, 3) float64 array in the file's units (docs/metrics.md 0). A mesh's or a
    curve file's vertices are accepted as points; so is an object (an Open3D PointCloud, ...)."""
    if not _is_path(path):
        return _point_set(_object_raw(path, "point cloud"), None, "point cloud")
    return _point_set(_read_raw(path), path, "point cloud")


def load_points(path: str | os.PathLike | object) -> np.ndarray:
    """A skeletal point set P_s (same formats, objects and checks as :func:`load_cloud`)."""
    if not _is_path(path):
        return _point_set(_object_raw(path, "skeletal point set"), None, "skeletal point set")
    return _point_set(_read_raw(path), path, "skeletal point set")


def _curve(raw: RawData, path: str | os.PathLike) -> CurveSkeleton:
    if raw.edges is None or len(raw.edges) == 0:
        raise SkelInputError(
            f"{raw.format} file has no edges: it is a point set, not a curve skeleton", path
        )
    with warnings.catch_warnings(record=True) as dropped:  # said below, unless nothing is left to score
        warnings.simplefilter("always")
        curve = CurveSkeleton.from_raw(raw.vertices, raw.edges, path, radius=raw.radius)
    if curve.n_edges == 0:  # every edge touched a NaN vertex or was a self-loop: one line, no warning before it
        bad = int((~np.all(np.isfinite(np.asarray(raw.vertices, dtype=float)), axis=1)).sum())
        why = (f"every edge touches one of its {bad} vertices with NaN coordinates" if bad
               else "every edge is a self-loop")
        raise SkelInputError(f"no edge left: {why}", path)
    for w in dropped:
        warnings.warn(w.message, w.category, stacklevel=3)
    if curve.n_vertices and np.all(curve.vertices == curve.vertices[0]):
        raise SkelInputError(f"all {curve.n_vertices} curve vertices are at the same position", path)
    return curve


def load_curve(path: str | os.PathLike | object) -> CurveSkeleton:
    """A curve skeleton G_s = (V, E), cleaned by :meth:`CurveSkeleton.from_raw` (docs/metrics.md 0: NaN vertices
    dropped with a warning, duplicate edges and self-loops dropped, out-of-range index an error), with
    its per-vertex radius when the file has one. A curve object (a LineSet, a networkx graph, ...) too."""
    if not _is_path(path):
        curve = CurveSkeleton.coerce(path, "curve skeleton")
        if curve.n_edges == 0:
            raise SkelInputError(f"curve skeleton: the {type(path).__name__} has no edges: it is a point set")
        if np.all(curve.vertices == curve.vertices[0]):
            raise SkelInputError(f"curve skeleton: all {curve.n_vertices} vertices are at the same position")
        return curve
    return _curve(_read_raw(path), path)


def load_any(path: str | os.PathLike) -> Loaded:
    """Load a dropped file: a file with edges (or in a curve-only format) is a curve, else points."""
    if not _is_path(path):
        from ..interop.objects_in import is_curve_object

        label = f"<{type(path).__name__}>"
        if is_curve_object(path):
            return Loaded(kind="curve", path=label, format=label, curve=load_curve(path))
        return Loaded(kind="points", path=label, format=label, points=load_cloud(path))
    raw = _read_raw(path)
    if raw.curve_format or (raw.edges is not None and len(raw.edges) > 0):
        return Loaded(kind="curve", path=str(path), format=raw.format, curve=_curve(raw, path))
    return Loaded(kind="points", path=str(path), format=raw.format, points=_point_set(raw, path, "point set"))
