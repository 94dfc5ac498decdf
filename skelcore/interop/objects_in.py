"""Other libraries' objects as SkelScope's inputs: a point set (:func:`points_of`) or a curve's
vertices, edges and radii (:func:`curve_parts`), read through the attributes each library documents
(Open3D ``points``/``lines``/``vertices``, trimesh ``vertices``/``entities``, networkx node attributes,
navis ``nodes``, cloud-volume ``vertices``/``edges``/``radii``, pandas columns). Nothing is imported here:
the object brings its library along. Unknown objects get one TypeError naming what is accepted.
"""

from __future__ import annotations

import numpy as np

from ..errors import SkelInputError
from .recognise import CURVE_KINDS, EXPECTED_CURVE, EXPECTED_POINTS, kind_of, type_name

__all__ = ["points_of", "curve_parts", "is_curve_object"]

#: node attributes holding a position (pc-skeletor: "pos"; networkx's GEXF reader: "viz")
_POSITION_KEYS = ("pos", "position", "positions", "xyz", "coords", "coordinates", "point", "location")
_RADIUS_KEYS = ("radius", "r", "radii")


def is_curve_object(obj: object) -> bool:
    """True for a recognised object that carries edges (a LineSet, a graph, a neuron, ...)."""
    return kind_of(obj) in CURVE_KINDS


def points_of(obj: object, name: str = "points") -> object:
    """An (N, 3) array of the object's points (a curve's vertices, a mesh's vertices), or the object
    itself when it is a plain array-like (the caller's ``np.asarray`` checks it as before)."""
    kind = kind_of(obj)
    if kind in ("array", "array_like"):
        return obj
    if kind is None:
        hint = " (a file name: load it with skelcore.load_cloud first)" if isinstance(obj, (str, bytes)) else ""
        raise TypeError(f"{name}: cannot use a {type_name(obj)}{hint}; expected {EXPECTED_POINTS}")
    if kind == "open3d_pointcloud" or kind == "open3d_lineset":
        return np.asarray(obj.points, dtype=np.float64)
    if kind == "open3d_mesh" or kind == "trimesh_points":
        return np.asarray(obj.vertices, dtype=np.float64)
    if kind == "frame":
        from .swc_frames import frame_points

        return frame_points(obj, name)
    return curve_parts(obj, name)[0]


def curve_parts(obj: object, name: str = "curve") -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """(vertices, edges, radius or None) of a curve given as any supported object (not yet cleaned:
    :meth:`skelcore.curve.CurveSkeleton.from_raw` does that)."""
    kind = kind_of(obj)
    if kind is None or kind in ("array", "array_like"):
        raise TypeError(f"{name}: cannot use a {type_name(obj)} as a curve skeleton; expected {EXPECTED_CURVE}")
    if kind in ("open3d_pointcloud", "open3d_mesh", "trimesh_points"):
        raise SkelInputError(
            f"{name}: a {type_name(obj)} has no edges: it is a point set, not a curve skeleton"
        )
    if kind == "pair":
        return obj[0], obj[1], None
    if kind == "mapping":
        v = obj.get("vertices", obj.get("points"))
        return v, obj.get("edges", np.empty((0, 2))), obj.get("radius", obj.get("radii"))
    if kind == "open3d_lineset":
        return np.asarray(obj.points, dtype=np.float64), np.asarray(obj.lines), None
    if kind == "skeleton":
        radii = getattr(obj, "radii", None)
        return np.asarray(obj.vertices, dtype=np.float64), np.asarray(obj.edges), radii
    if kind == "trimesh_path":
        return _path_parts(obj, name)
    if kind == "networkx_graph":
        return _graph_parts(obj, name)
    from .swc_frames import frame_curve_parts

    return frame_curve_parts(obj.nodes if kind == "navis_neuron" else obj, name)  # "swc_frame", "frame"


def _path_parts(path, name: str) -> tuple[np.ndarray, np.ndarray, None]:
    """trimesh Path3D: each entity's consecutive point indices are edges (a Line's segments; for arcs
    and splines, their control polygon)."""
    v = np.asarray(path.vertices, dtype=np.float64)
    if v.ndim != 2 or v.shape[1] != 3:
        raise SkelInputError(f"{name}: trimesh path vertices have shape {v.shape}, expected (N, 3) (a Path3D)")
    chains = [np.asarray(ent.points, dtype=np.int64).ravel() for ent in path.entities]
    pairs = [np.column_stack([c[:-1], c[1:]]) for c in chains if len(c) >= 2]
    edges = np.concatenate(pairs) if pairs else np.empty((0, 2), np.int64)
    return v, edges, None


def _graph_parts(graph, name: str) -> tuple[np.ndarray, np.ndarray, np.ndarray | None]:
    """networkx graph: a position per node from a "pos"-like attribute (array of 3), x/y/z
    attributes, or GEXF's viz position; node order is the graph's; a "radius" attribute is kept."""
    nodes = list(graph.nodes(data=True))
    if not nodes:
        raise SkelInputError(f"{name}: the networkx graph has no nodes")
    positions = [_node_position(attrs) for _, attrs in nodes]
    missing = next((k for k, p in enumerate(positions) if p is None), None)
    if missing is not None:
        keys = ", ".join(map(str, nodes[missing][1])) or "none"
        raise SkelInputError(
            f"{name}: networkx node {nodes[missing][0]!r} has no position (expected a 'pos' attribute or x, y, z; "
            f"its attributes: {keys})"
        )
    try:
        v = np.array(positions, dtype=np.float64)
    except (TypeError, ValueError):
        raise SkelInputError(f"{name}: networkx node positions are not all 3 numbers") from None
    if v.ndim != 2 or v.shape[1] != 3:
        raise SkelInputError(f"{name}: networkx node positions have shape {v.shape}, expected (N, 3)")
    index = {node: k for k, (node, _) in enumerate(nodes)}
    edges = np.array([(index[a], index[b]) for a, b, *_ in graph.edges], dtype=np.int64).reshape(-1, 2)
    key = next((k for k in _RADIUS_KEYS if all(k in attrs for _, attrs in nodes)), None)
    radius = None if key is None else np.array([attrs[key] for _, attrs in nodes], dtype=np.float64)
    return v, edges, radius


def _node_position(attrs: dict) -> object | None:
    for key in _POSITION_KEYS:
        if key in attrs:
            return np.asarray(attrs[key], dtype=np.float64).ravel().tolist()
    if all(k in attrs for k in "xyz"):
        return [attrs["x"], attrs["y"], attrs["z"]]
    viz = attrs.get("viz")
    if isinstance(viz, dict) and isinstance(viz.get("position"), dict):
        pos = viz["position"]
        return [pos.get("x", 0.0), pos.get("y", 0.0), pos.get("z", 0.0)]
    return None
