"""An Evaluation's defects as the viewer lists and draws them (with a scan's
openings and stray points), without Qt.

:func:`defect_rows` turns ``Evaluation.diagnostics`` (skelcore/diagnostics/record.py), its warnings and
its ``scan`` block into one :class:`DefectRow` per defect found: missing parts, spurious branches,
spurious and missing cycles, branches outside the shape, ``collapse``, ``frame``, ``open_surface`` (one
row per opening), ``outliers``, ``thin_parts`` and ``sparse_boundedness`` (the scan's: no defects of the
skeleton), each with its size in the engine's words and the geometry that frames and highlights it.
:func:`branch_details` is a clicked branch: length, local radius, the metric
means along it and its flags. Positions are in the user's units (the layers'); the engine's lengths are
normalized (docs/metrics.md 0) and are turned back with ``Evaluation.normalization``.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any

import numpy as np

__all__ = ["DefectRow", "DEFECT_TITLES", "defect_rows", "branch_flags", "branch_details", "branch_paths",
           "opening_path", "rim_spacing", "defect_counts", "sound_line", "branch_edges", "branch_points"]

#: the words a row starts with, per warning code (the CLI's defects block uses the codes themselves)
DEFECT_TITLES = {
    "incomplete": "missing part",
    "spurious_branches": "spurious branch",
    "spurious_cycles": "spurious cycle",
    "missing_cycles": "missing cycle",
    "outside": "outside the shape",
    "disconnected": "broken curve",
    "along_surface": "along the surface",
    "collapse": "collapse",
    "frame": "frame",
    "open_surface": "opening",
    "outliers": "stray points",
    "thin_parts": "thin parts",
    "sparse_boundedness": "sparse sampling",
}
_NO_PLACE = np.zeros((0, 3))


@dataclass
class DefectRow:
    """One defect: its warning ``code``, a short ``title``, its ``size`` in the engine's words, the
    skeleton ``column`` it belongs to ("curve", "skeletal" or "" for the scan), and what to draw:
    ``cloud_rows`` (rows of ``Evaluation.cloud``), ``branches`` (curve branch ids), ``edges`` (curve edge
    ids) and ``points`` (every position that frames it: its bounding box is where the camera goes)."""

    code: str
    title: str
    size: str
    column: str = ""
    cloud_rows: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    branches: tuple[int, ...] = ()
    edges: np.ndarray = field(default_factory=lambda: np.zeros(0, np.int64))
    points: np.ndarray = field(default_factory=lambda: _NO_PLACE)

    def bounds(self) -> tuple[np.ndarray, np.ndarray] | None:
        """(lo, hi) corners of the box the camera frames, None when the defect has no place (then the
        whole scene)."""
        if not len(self.points):
            return None
        return self.points.min(axis=0), self.points.max(axis=0)


def _scale(ev: Any) -> float:
    norm = getattr(ev, "normalization", None)
    return float(norm.scale) if norm is not None and getattr(norm, "scale", 0) else 1.0


def _summary(ev: Any) -> dict[str, Any]:
    diag = getattr(ev, "diagnostics", None)
    return {} if diag is None else (diag.summary or {})


def _arrays(ev: Any) -> dict[str, np.ndarray]:
    diag = getattr(ev, "diagnostics", None)
    return {} if diag is None else (diag.arrays or {})


def branch_paths(ev: Any) -> list[np.ndarray]:
    """Each branch's curve vertices in order (the JSON branch list), empty without a curve's diagnostics."""
    branches = (_summary(ev).get("branches") or {}).get("branches") or []
    return [np.asarray(b["vertices"], dtype=np.int64) for b in branches]


def _curve(ev: Any) -> Any:
    return None if getattr(ev, "curve", None) is None else ev.curve.curve


def branch_edges(ev: Any, ids: list[int] | tuple[int, ...]) -> np.ndarray:
    """The curve edges of branches ``ids`` (consecutive vertices of their paths)."""
    curve = _curve(ev)
    paths = branch_paths(ev)
    if curve is None or not paths:
        return np.zeros(0, np.int64)
    edges = np.sort(np.asarray(curve.edges, dtype=np.int64).reshape(-1, 2), axis=1)
    pairs = [np.sort(np.column_stack([p[:-1], p[1:]]), axis=1) for i in ids if 0 <= i < len(paths)
             for p in [paths[i]] if len(p) > 1]
    if not pairs:
        return np.zeros(0, np.int64)
    want = np.unique(np.vstack(pairs), axis=0)
    n = int(max(edges.max(initial=0), want.max(initial=0))) + 1
    key = edges[:, 0] * n + edges[:, 1]
    return np.flatnonzero(np.isin(key, want[:, 0] * n + want[:, 1]))


def branch_points(ev: Any, ids: list[int] | tuple[int, ...]) -> np.ndarray:
    curve = _curve(ev)
    paths = branch_paths(ev)
    if curve is None or not paths:
        return _NO_PLACE
    verts = np.asarray(curve.vertices, dtype=float)
    idx = [paths[i] for i in ids if 0 <= i < len(paths)]
    return verts[np.concatenate(idx)] if idx else _NO_PLACE


def branch_flags(ev: Any) -> list[tuple[str, ...]]:
    """Per branch, the defect codes found on it: its samples' (or vertices') defect bits
    (``skelcore.diagnostics.record.DEFECT_BITS``), the spurious-branch verdicts and the outside lengths over the threshold."""
    from skelcore.diagnostics.record import DEFECT_BITS  # at use: the window's first frame needs no engine

    paths = branch_paths(ev)
    if not paths:
        return []
    flags: list[set[str]] = [set() for _ in paths]
    arrays = _arrays(ev)
    for where in ("sample", "vertex"):
        branch, bits = arrays.get(f"curve_{where}_branch"), arrays.get(f"curve_{where}_defects")
        if branch is None or bits is None or len(branch) != len(bits):
            continue
        for code, bit in DEFECT_BITS.items():
            on = np.unique(branch[(bits & bit) != 0])
            for b in on[(on >= 0) & (on < len(paths))]:
                flags[int(b)].add(code)
    summary = _summary(ev)
    for spur in (summary.get("spurious_branches") or {}).get("branches") or []:
        if spur.get("spurious") and 0 <= spur["id"] < len(paths):
            flags[spur["id"]].add("spurious_branches")
    params = getattr(ev, "params", None)
    min_radii = float(getattr(params, "outside_min_radii", 0.5))
    for out in (summary.get("outside") or {}).get("branches") or []:
        if out.get("radii", 0.0) >= min_radii and 0 <= out["id"] < len(paths):
            flags[out["id"]].add("outside")
    return [tuple(code for code in DEFECT_TITLES if code in f) for f in flags]


def _warnings(ev: Any) -> list[Any]:
    return list(getattr(ev, "warnings", None) or [])


def _codes(ev: Any) -> set[str]:
    return {w.code for w in _warnings(ev)}


def _missing_rows(ev: Any) -> list[DefectRow]:
    from skelcore.diagnostics.missing_parts import depth_clause  # the engine's words for a depth

    summary, arrays = _summary(ev), _arrays(ev)
    cloud = None if getattr(ev, "cloud", None) is None else np.asarray(ev.cloud, dtype=float)
    rows = []
    for column, what in (("curve", "curve skeleton"), ("skeletal", "skeletal set")):
        mp = (summary.get("missing_parts") or {}).get(column)
        if not mp or not mp.get("incomplete"):
            continue
        region = arrays.get(f"cloud_missing_{column}")
        counted = [r for r in mp.get("regions") or [] if r.get("counted")]
        for r in counted:
            sel = np.flatnonzero(region == r["id"]) if region is not None else np.zeros(0, np.int64)
            pts = cloud[sel] if cloud is not None and len(sel) and sel.max() < len(cloud) else _NO_PLACE
            rows.append(DefectRow(
                "incomplete", f"missing part ({what})",
                f"{r['share']:.1%} of the cloud, {r['n_points']} points"
                f"{depth_clause(r.get('depth'), 'the skeleton')}", column, sel, points=pts))
        if not counted:
            rows.append(DefectRow("incomplete", f"incomplete ({what})",
                                  f"explains only {mp['completeness']:.1%} of the cloud (completeness "
                                  f"{mp['completeness']:.3f})", column))
    return rows


def _spur_rows(ev: Any) -> list[DefectRow]:
    spurs = _summary(ev).get("spurious_branches") or {}
    branches = (_summary(ev).get("branches") or {}).get("branches") or []
    total = sum(b["length"] for b in branches) or 1.0
    rows = []
    for s in spurs.get("branches") or []:
        if not s.get("spurious"):
            continue
        b = s["id"]
        length = branches[b]["length"] if b < len(branches) else float("nan")
        radii = "" if s.get("length_radii") is None else f"{s['length_radii']:.2g} local radii long, "
        rows.append(DefectRow("spurious_branches", f"spurious branch #{b}",
                              f"{radii}{length / total:.1%} of the curve's length; its end {s.get('reach') or 0:.2g} "
                              f"junction radii out, {s.get('unique', 0)} of its {s.get('territory', 0)} nearest cloud "
                              "points explained by it alone", "curve", branches=(b,),
                              edges=branch_edges(ev, (b,)), points=branch_points(ev, (b,))))
    return rows


def _cycle_rows(ev: Any) -> list[DefectRow]:
    summary = _summary(ev)
    cycles = summary.get("cycles") or {}
    basis = (summary.get("branches") or {}).get("cycles") or []
    branches = (summary.get("branches") or {}).get("branches") or []
    total = sum(b["length"] for b in branches) or 1.0
    rows = []
    codes = _codes(ev)
    if "spurious_cycles" in codes:
        for c in cycles.get("spurious_cycles") or []:
            ids = tuple(int(b) for b, _sign in basis[c]) if c < len(basis) else ()
            length = sum(branches[b]["length"] for b in ids if b < len(branches))
            rows.append(DefectRow("spurious_cycles", f"spurious cycle #{c}",
                                  f"goes around no tunnel of the shape ({cycles.get('shape', 0)} found); "
                                  f"{len(ids)} branches, {length / total:.1%} of the curve's length", "curve",
                                  branches=ids, edges=branch_edges(ev, ids), points=branch_points(ev, ids)))
    if "missing_cycles" in codes:
        rows.append(DefectRow("missing_cycles", "missing cycle",
                              f"the shape has {cycles.get('shape', 0)} tunnels and the curve's {cycles.get('skeleton', 0)} "
                              f"cycles go around {cycles.get('linked', 0)}: {cycles.get('missing', 0)} missing", "curve"))
    return rows


def _outside_rows(ev: Any) -> list[DefectRow]:
    """One row per branch with at least ``outside_min_radii`` local radii outside the shape; the
    warning's own words when it fired on the length share alone, or for the skeletal set."""
    if "outside" not in _codes(ev):
        return []
    out = _summary(ev).get("outside") or {}
    min_radii = float(getattr(getattr(ev, "params", None), "outside_min_radii", 0.5))
    scale = _scale(ev)
    flagged = _outside_edges(ev, _arrays(ev))
    curve = _curve(ev)

    def edge_points(edges: np.ndarray) -> np.ndarray:
        if curve is None or not len(edges):
            return _NO_PLACE
        return np.asarray(curve.vertices, float)[np.asarray(curve.edges).reshape(-1, 2)[edges].ravel()]

    rows = []
    for b in out.get("branches") or []:
        if b["radii"] < min_radii:
            continue
        edges = np.intersect1d(branch_edges(ev, (b["id"],)), flagged)
        pts = edge_points(edges) if len(edges) else branch_points(ev, (b["id"],))
        rows.append(DefectRow("outside", f"branch #{b['id']} outside the shape",
                              f"{b['length'] / scale:.3g} long outside ({b['radii']:.2g} local radii), up to "
                              f"{b['depth']:.2g} local radii out", "curve", branches=(b["id"],), edges=edges, points=pts))
    for w in _warnings(ev):
        if w.code != "outside":
            continue
        if "skeletal points" in w.message:
            rows.append(DefectRow("outside", "skeletal points outside the shape", w.message, "skeletal"))
        elif not any(r.column == "curve" for r in rows):  # fired on the length share alone
            rows.append(DefectRow("outside", "outside the shape", w.message, "curve", edges=flagged,
                                  points=edge_points(flagged)))
    return rows


def _piece_rows(ev: Any) -> list[DefectRow]:
    """One row per extra piece of the curve (``disconnected``, docs/diagnostics.md "Disconnected"):
    its branches, length and place; the warning's own words when the pieces' branches are not known."""
    if "disconnected" not in _codes(ev):
        return []
    from skelcore.diagnostics.pieces import curve_pieces  # at use: the window's first frame needs no engine

    info = _summary(ev).get("components") or {}
    ids = [int(b) for b in info.get("branches") or []]
    curve = _curve(ev)
    rows: list[DefectRow] = []
    if curve is not None and ids:
        _n, piece = curve_pieces(curve)
        edges = np.asarray(curve.edges, np.int64).reshape(-1, 2)
        by_piece: dict[int, list[int]] = {}
        for b in ids:
            e = branch_edges(ev, (b,))
            if len(e):
                by_piece.setdefault(int(piece[edges[e[0], 0]]), []).append(b)
        branches = (_summary(ev).get("branches") or {}).get("branches") or []
        total = sum(b["length"] for b in branches) or 1.0
        for k, members in enumerate(by_piece.values(), start=1):
            length = sum(branches[b]["length"] for b in members if b < len(branches))
            rows.append(DefectRow("disconnected", f"broken curve: piece {k} of {len(by_piece)} apart",
                                  f"{len(members)} branches, {length / total:.1%} of the curve's length, apart from "
                                  f"the curve's main piece in one piece of the cloud", "curve",
                                  branches=tuple(members), edges=branch_edges(ev, tuple(members)),
                                  points=branch_points(ev, tuple(members))))
    if not rows:
        rows = [DefectRow("disconnected", DEFECT_TITLES["disconnected"], w.message, "curve")
                for w in _warnings(ev) if w.code == "disconnected"]
    return rows


def _surface_rows(ev: Any) -> list[DefectRow]:
    """One row per branch running along the surface (``along_surface``, docs/diagnostics.md "Along the surface")."""
    if "along_surface" not in _codes(ev):
        return []
    rows = []
    for b in (_summary(ev).get("along_surface") or {}).get("branches") or []:
        radii = "" if b.get("radii") is None else f"{b['radii']:.2g} local radii, "
        rows.append(DefectRow("along_surface", f"branch #{b['id']} along the surface",
                              f"{radii}{b['centeredness']:.2g} cross-section radii from the wall (median), "
                              f"{b['samples_off']} of its {b['samples']} samples off axis", "curve",
                              branches=(b["id"],), edges=branch_edges(ev, (b["id"],)),
                              points=branch_points(ev, (b["id"],))))
    return rows


def _outside_edges(ev: Any, arrays: dict[str, np.ndarray]) -> np.ndarray:
    """Curve edges holding a sample flagged ``outside``."""
    from skelcore.diagnostics.record import DEFECT_BITS

    bits = arrays.get("curve_sample_defects")
    if bits is None or getattr(ev, "curve", None) is None or ev.curve.sample_edge is None:
        return np.zeros(0, np.int64)
    edge = np.asarray(ev.curve.sample_edge, dtype=np.int64)
    if len(edge) != len(bits):
        return np.zeros(0, np.int64)
    return np.unique(edge[(bits & DEFECT_BITS["outside"]) != 0])


def _trust_rows(ev: Any) -> list[DefectRow]:
    """``collapse`` and ``frame``: the warning's own words; placed on the skeleton they name."""
    rows = []
    for w in _warnings(ev):
        if w.code not in ("collapse", "frame"):
            continue
        column = "skeletal" if "skeletal" in w.message else "curve"
        pts = _NO_PLACE
        if column == "curve" and _curve(ev) is not None:
            pts = np.asarray(_curve(ev).vertices, dtype=float)
        elif getattr(ev, "skeletal", None) is not None:
            pts = np.asarray(ev.skeletal.points, dtype=float)
        rows.append(DefectRow(w.code, DEFECT_TITLES[w.code], w.message, column, points=pts))
    return rows


#: an opening's drawn path joins rim points at most this many times the rim's spacing apart
RIM_LINK = 4.0
#: side branches of a rim's path with fewer points are left out (the twigs of a rim a few points wide)
RIM_BRANCH = 4


def rim_spacing(points: np.ndarray) -> float:
    """The rim's spacing: the median distance from a rim point to its nearest other (0 for fewer than 2)."""
    from scipy.spatial import cKDTree  # on first use: a cloud's first frame needs no KD-tree (start-up)

    pts = np.asarray(points, dtype=float)
    if len(pts) < 2:
        return 0.0
    d, _ = cKDTree(pts).query(pts, k=2)
    return float(np.median(d[:, 1]))


def opening_path(points: np.ndarray, link: float = RIM_LINK) -> tuple[np.ndarray, np.ndarray]:
    """An opening's rim drawn as the rim's own path: ``(vertices, pairs)`` of segments that never join
    rim points more than ``link`` x the rim's spacing (:func:`rim_spacing`) apart.

    The rim points are linked to their neighbours within that distance and each connected piece's
    minimum spanning tree is drawn as paths: its longest (the rim followed from one end to the other,
    closed when its ends are neighbours: a rim all round its opening), then the longest of what is left,
    each joined to the drawn part by its tree edge, down to :data:`RIM_BRANCH` points (the side twigs of
    a rim a few points wide are left out). A one-sided scan's rim is a long thin band: sorting it by angle
    around its centre would draw chords across the shape."""
    from scipy.sparse import coo_matrix
    from scipy.sparse.csgraph import connected_components, minimum_spanning_tree
    from scipy.spatial import cKDTree

    pts = np.asarray(points, dtype=float)
    none = (np.zeros((0, 3)), np.zeros((0, 2), dtype=np.int64))
    spacing = rim_spacing(pts)
    if not spacing > 0:
        return none
    reach = float(link) * spacing
    pairs = cKDTree(pts).query_pairs(reach, output_type="ndarray")
    if not len(pairs):
        return none
    n = len(pts)
    length = np.linalg.norm(pts[pairs[:, 0]] - pts[pairs[:, 1]], axis=1) + 1e-9 * spacing  # 0 = no edge
    tree = minimum_spanning_tree(coo_matrix((length, (pairs[:, 0], pairs[:, 1])), shape=(n, n))).tocsr()
    tree = (tree + tree.T).tocsr()
    segments: list[tuple[int, int]] = []
    drawn = np.zeros(n, dtype=bool)
    left = np.ones(n, dtype=bool)
    first = True
    while True:
        nodes = np.flatnonzero(left)
        if not len(nodes):
            break
        sub = tree[nodes][:, nodes]
        n_pieces, label = connected_components(sub, directed=False)
        sizes = np.bincount(label, minlength=n_pieces)
        grown = False
        for piece in np.flatnonzero(sizes >= (2 if first else RIM_BRANCH)):
            members = nodes[label == piece]
            path = members[_longest_path(tree[members][:, members])]
            segments += list(zip(path[:-1].tolist(), path[1:].tolist()))
            if first and len(path) >= 4 and np.linalg.norm(pts[path[0]] - pts[path[-1]]) <= reach:
                segments.append((int(path[-1]), int(path[0])))
            joins = tree[path][:, np.flatnonzero(drawn)].tocoo()  # the tree edge to the part drawn before
            segments += [(int(path[i]), int(np.flatnonzero(drawn)[j])) for i, j in zip(joins.row, joins.col)]
            drawn[path] = True
            grown = True
        left = ~drawn & left
        left[nodes[np.isin(label, np.flatnonzero(sizes < RIM_BRANCH))]] = False
        first = False
        if not grown:
            break
    if not segments:
        return none
    used = np.unique(np.asarray(segments).ravel())
    index = np.full(n, -1, dtype=np.int64)
    index[used] = np.arange(len(used))
    return pts[used], index[np.asarray(segments, dtype=np.int64)]


def _longest_path(tree: Any) -> np.ndarray:
    """The longest path (by length) of a tree, as its node indices: farthest from any node, then farthest
    from that one (the tree's diameter)."""
    from scipy.sparse.csgraph import dijkstra

    dist = dijkstra(tree, directed=False, indices=0)
    a = int(np.argmax(np.where(np.isfinite(dist), dist, -1.0)))
    dist, previous = dijkstra(tree, directed=False, indices=a, return_predecessors=True)
    b = int(np.argmax(np.where(np.isfinite(dist), dist, -1.0)))
    path = [b]
    while path[-1] != a:
        path.append(int(previous[path[-1]]))
    return np.asarray(path[::-1], dtype=np.int64)


def _scan_rows(ev: Any) -> list[DefectRow]:
    scan = getattr(ev, "scan", None)
    cloud = None if getattr(ev, "cloud", None) is None else np.asarray(ev.cloud, dtype=float)
    rows = []
    if scan is None:
        return rows
    codes = _codes(ev)
    for i, o in enumerate(scan.openings or []):
        sel = np.asarray(o.get("rows") or [], dtype=np.int64)
        pts = cloud[sel] if cloud is not None and len(sel) and sel.max() < len(cloud) else _NO_PLACE
        kind = "open tube end" if o.get("kind") == "end" else "missing side"
        size = "" if not np.isfinite(o.get("size", np.nan)) else f"{o['size']:.3g} local radii wide, "
        state = " (capped)" if o.get("capped") else ""
        rows.append(DefectRow("open_surface", f"opening #{i}: {kind}{state}",
                              f"{size}{o.get('extent', 0):.3g} across, {o.get('n_rim', len(sel))} rim points"
                              + ("" if "open_surface" in codes else " (too small to change boundedness)"),
                              "", sel, points=pts))
    found = scan.outliers or {}
    if found.get("count"):
        sel = np.asarray(found.get("rows") or [], dtype=np.int64)
        message = next((w.message for w in _warnings(ev) if w.code == "outliers"), "")
        removed = " (removed: evaluated without them)" if scan.outliers_removed else ""
        pts = _NO_PLACE
        if not scan.outliers_removed and cloud is not None and len(sel) and sel.max() < len(cloud):
            pts = cloud[sel]
        rows.append(DefectRow("outliers", f"{found['count']} stray points{removed}",
                              message or f"bounding box {found.get('scale_ratio', 1):.3g} x as large", "",
                              sel if not scan.outliers_removed else np.zeros(0, np.int64), points=pts))
    rows += _thin_rows(ev, scan, cloud) + _sparse_rows(ev, scan)
    return rows


def _message(ev: Any, code: str) -> str:
    return next((w.message for w in _warnings(ev) if w.code == code), "")


def _thin_rows(ev: Any, scan: Any, cloud: np.ndarray | None) -> list[DefectRow]:
    """``thin_parts``: one row for the parts sampled too thinly to resolve, highlighting their boundary
    points when the record carries their rows, else framing their box."""
    thin = getattr(scan, "thin_parts", None) or {}
    if not thin.get("parts"):
        return []
    sel = np.asarray(thin.get("rows") or [], dtype=np.int64)
    if cloud is not None and len(sel) and sel.max() < len(cloud):
        pts = cloud[sel]
    else:
        sel = np.zeros(0, np.int64)
        box = np.asarray(thin.get("box") or [], dtype=float)
        pts = box.reshape(-1, 3) if box.size == 6 and np.isfinite(box).all() else _NO_PLACE
    n = int(thin["parts"])
    size = (f"{thin.get('points', 0)} boundary points, {thin.get('share', 0.0):.1%} of the cloud, sampled too "
            "thinly to resolve: their gaps are not openings, and boundedness there counts rays through them")
    return [DefectRow("thin_parts", f"{n} thin part{'s' if n != 1 else ''}", size, "", sel, points=pts)]


def _sparse_rows(ev: Any, scan: Any) -> list[DefectRow]:
    """``sparse_boundedness``: one row (no place: the whole scene) with the share of each skeleton's
    elements unbounded where the cloud is sampled sparsely."""
    shares = getattr(scan, "sparse", None) or {}
    message = _message(ev, "sparse_boundedness")
    if not shares and not message:
        return []
    names = {"skeletal": "skeletal points", "curve": "curve samples"}
    which = " and ".join(f"{share:.0%} of the {names.get(col, col)}" for col, share in shares.items())
    return [DefectRow("sparse_boundedness", "boundedness falls with sparse sampling",
                      message or f"{which} are unbounded where the cloud is sampled sparsely", "")]


def defect_rows(ev: Any) -> list[DefectRow]:
    """Every defect of ``ev`` found without a reference, in the order of the CLI's defects block, then the
    scan's openings, stray points, thin parts and sparse sampling; [] for None."""
    if ev is None:
        return []
    return (_missing_rows(ev) + _spur_rows(ev) + _cycle_rows(ev) + _outside_rows(ev) + _piece_rows(ev)
            + _surface_rows(ev) + _trust_rows(ev) + _scan_rows(ev))


def defect_counts(ev: Any) -> dict[str, int]:
    """Rows per code (the A/B table's defect lines)."""
    out: dict[str, int] = {}
    for row in defect_rows(ev):
        out[row.code] = out.get(row.code, 0) + 1
    return out


def sound_line(ev: Any) -> str:
    """"sound" when no defect warning (:data:`skelcore.diagnostics.trust.DEFECT_CODES`) was raised, as compare's
    "sound" column says, else "not sound: " and the codes; then the defect checks that did not run
    ("not checked: outside (why)", docs/diagnostics.md "Checks not run")."""
    from skelcore.diagnostics.trust import defect_codes, unchecked_defects

    codes = defect_codes(_warnings(ev)) if ev is not None else []
    line = "sound" if not codes else "not sound: " + ", ".join(codes)
    skipped = unchecked_defects(getattr(ev, "not_computed", None))
    if skipped:
        line += "; not checked: " + "; ".join(f"{code} ({why})" for code, why in skipped.items())
    return line


def branch_details(ev: Any, branch: int, beta_star: float | None = None) -> dict[str, Any]:
    """A branch of the curve as the info panel shows it: its length (user units), local radius
    (median, min, max), the means of each local metric along it (samples for boundedness and
    centeredness, docs/metrics.md 3; vertices for smoothness, docs/metrics.md 4), its ends' degrees, kind and flags."""
    branches = (_summary(ev).get("branches") or {}).get("branches") or []
    if not 0 <= branch < len(branches):
        raise ValueError(f"no branch {branch} (the curve has {len(branches)})")
    b = branches[branch]
    scale = _scale(ev)
    radius = {k: (None if v is None else v / scale) for k, v in (b.get("radius") or {}).items()}
    means: dict[str, float] = {}
    c = getattr(ev, "curve", None)
    arrays = _arrays(ev)
    if c is not None:
        sb = arrays.get("curve_sample_branch")
        beta = beta_star if beta_star is not None else float(ev.params.beta_star)
        if sb is not None and len(sb) == len(c.sample_boundedness):
            on = sb == branch
            if not on.any():  # a branch shorter than the sample spacing: the samples on its edges
                on = np.isin(np.asarray(c.sample_edge), branch_edges(ev, (branch,)))
            for name, values in (("boundedness", c.sample_boundedness), ("centeredness", c.sample_centeredness(beta))):
                v = np.asarray(values, dtype=float)[on]
                means[name] = float(np.nanmean(v)) if np.isfinite(v).any() else float("nan")
        verts = np.asarray(b["vertices"], dtype=np.int64)
        sm = np.asarray(c.vertex_smoothness, dtype=float)
        if len(verts) and verts.max() < len(sm):
            v = sm[verts]
            means["smoothness"] = float(np.nanmean(v)) if np.isfinite(v).any() else float("nan")
    flags = branch_flags(ev)
    return {"branch": int(branch), "kind": b.get("kind", ""), "length": float(b["length"]) / scale,
            "radius": radius, "end_degrees": list(b.get("end_degrees") or []), "n_vertices": len(b["vertices"]),
            "means": means, "flags": list(flags[branch]) if branch < len(flags) else []}
