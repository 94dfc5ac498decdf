"""Which library object is this? Recognised by its attributes and its type's module, never by
importing the library (Open3D alone is 400 MB): SkelScope has no hard dependency on any of them.

Each kind names what :mod:`.objects_in` reads from it; :data:`EXPECTED_POINTS` and
:data:`EXPECTED_CURVE` are the one-line lists an unknown object's TypeError gives.
"""

from __future__ import annotations

import numpy as np

__all__ = ["kind_of", "type_name", "EXPECTED_POINTS", "EXPECTED_CURVE", "CURVE_KINDS"]

EXPECTED_POINTS = (
    "an (N, 3) array-like, an Open3D PointCloud / LineSet / TriangleMesh, a trimesh PointCloud / Trimesh / "
    "Path3D, a networkx graph with node positions, a navis TreeNeuron, a cloud-volume / kimimaro Skeleton "
    "or a pandas DataFrame with x, y, z columns"
)
EXPECTED_CURVE = (
    "a CurveSkeleton, a (vertices, edges) pair, a {'vertices', 'edges'} dict, an Open3D LineSet, a trimesh "
    "Path3D, a networkx graph with node positions, a navis TreeNeuron, a cloud-volume / kimimaro Skeleton "
    "or a pandas DataFrame of SWC rows"
)

#: kinds that carry edges (a curve skeleton); the others are point sets
CURVE_KINDS = frozenset({"open3d_lineset", "trimesh_path", "networkx_graph", "navis_neuron", "skeleton",
                         "swc_frame", "pair", "mapping"})


def type_name(obj: object) -> str:
    """``module.Class`` of an object, for messages (``open3d.cpu.pybind.geometry.LineSet``)."""
    t = type(obj)
    return f"{t.__module__}.{t.__qualname__}" if t.__module__ != "builtins" else t.__qualname__


def _has(obj: object, *names: str) -> bool:
    """Every name is an attribute of the object's class or the object (a failing property is "no")."""
    try:
        return all(hasattr(type(obj), n) or hasattr(obj, n) for n in names)
    except Exception:  # an object's __getattr__ may raise anything; then it is not what we look for
        return False


def _module(obj: object) -> str:
    return type(obj).__module__ or ""


def _swc_columns(columns) -> bool:
    from .swc_frames import swc_columns

    return swc_columns(columns) is not None


def kind_of(obj: object) -> str | None:
    """The kind of ``obj`` (``"array"``, ``"open3d_pointcloud"``, ``"open3d_lineset"``,
    ``"open3d_mesh"``, ``"trimesh_points"``, ``"trimesh_path"``, ``"networkx_graph"``,
    ``"navis_neuron"``, ``"skeleton"``, ``"swc_frame"``, ``"frame"``, ``"pair"``, ``"mapping"``,
    ``"array_like"``), or None for an object SkelScope does not know."""
    if isinstance(obj, np.ndarray):
        return "array"
    if isinstance(obj, (str, bytes)):
        return None
    mod = _module(obj)
    if mod.startswith("open3d") or _has(obj, "has_points") or _has(obj, "has_triangles"):
        if _has(obj, "points", "lines"):
            return "open3d_lineset"
        if _has(obj, "vertices", "triangles"):
            return "open3d_mesh"
        if _has(obj, "points"):
            return "open3d_pointcloud"
    if _has(obj, "columns", "to_numpy"):  # a pandas DataFrame
        return "swc_frame" if _swc_columns(obj.columns) else "frame"
    if mod.startswith("navis") or (_has(obj, "nodes") and not _has(obj, "adj") and _has(obj.nodes, "columns")):
        return "navis_neuron"
    if _has(obj, "adj", "nodes", "edges"):  # networkx Graph, DiGraph, MultiGraph
        return "networkx_graph"
    if _has(obj, "vertices", "edges", "radii"):  # osteoid / cloud-volume / kimimaro Skeleton
        return "skeleton"
    if _has(obj, "vertices", "entities"):  # trimesh Path3D
        return "trimesh_path"
    if mod.startswith("trimesh") and _has(obj, "vertices"):  # trimesh PointCloud, Trimesh
        return "trimesh_points"
    if isinstance(obj, dict):
        return "mapping" if any(k in obj for k in ("vertices", "points")) else None
    if isinstance(obj, (tuple, list)) and len(obj) == 2 and _looks_like_edges(obj[1]):
        return "pair"
    if isinstance(obj, (tuple, list)) or _has(obj, "__array__") or _has(obj, "__array_interface__"):
        return "array_like"
    return None


def _looks_like_edges(second: object) -> bool:
    """The second item of a (vertices, edges) pair: rows of two (or nothing)."""
    try:
        e = np.asarray(second)
    except Exception:  # ragged or exotic: not a pair
        return False
    return e.size == 0 or (e.ndim == 2 and e.shape[1] == 2)
