"""Real shapes with ground truth: the traced neurons of ``resources/neurons`` (docs/benchmark.md,
"The real suite: traced neurons").

A neuron is a decimated surface mesh (OBJ with faces, :func:`skelcore.io.mesh.read_obj_mesh`) and the
skeleton its proofreaders traced (SWC with radii, read by skelcore's SWC reader), in one frame.
:class:`MeshSampler` draws exact uniform samples of the mesh's surface (a triangle picked with
probability proportional to its area, a point uniform in it by folded barycentric coordinates), each
with its triangle's outward normal and a local radius (the nearest SWC node's), so the generator's
scan effects (:mod:`.scan_effects`) apply unchanged. :func:`node_facts` says, for every SWC node,
whether it lies inside the mesh (the generalized winding number over all triangles, |w| > 1/2, which
stays meaningful on a mesh with holes) and how far from the surface it is (exact point-to-triangle
distance), in units and in the node's radii: what a verdict about the traced skeleton must know,
since about half the nodes of these decimated meshes lie outside them.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from scipy.spatial import cKDTree

from ..curve import CurveSkeleton
from ..io.mesh import TriangleMesh, read_obj_mesh
from .surface_sampling import SurfacePoints

__all__ = ["NEURON_DIR", "NEURON_IDS", "Neuron", "load_neuron", "MeshSampler", "winding_numbers",
           "inside_mesh", "surface_distance", "NodeFacts", "node_facts", "write_facts_csv", "read_outside_radii",
           "TWIG_RADIUS"]

#: the folder of the shipped neurons (the source tree's resources/neurons)
NEURON_DIR = Path(__file__).resolve().parents[2] / "resources" / "neurons"
#: the five DA1 projection neurons shipped there, in a fixed order
NEURON_IDS = ("722817260", "754534424", "754538881", "1734350788", "1734350908")
#: a twig: an SWC node of radius below this many units (8 nm voxels); most outside nodes are on twigs
TWIG_RADIUS = 15.0
_CHUNK = 1 << 19  # point x triangle (or group) pairs held at once by the winding number (about 100 MB)


@dataclass(frozen=True)
class Neuron:
    """A neuron's mesh and its traced skeleton (radius per vertex; ``node_ids`` the SWC ids)."""

    name: str
    mesh: TriangleMesh
    skeleton: CurveSkeleton
    node_ids: np.ndarray


def load_neuron(name: str, folder: str | os.PathLike | None = None) -> Neuron:
    """``{name}.obj`` and ``{name}.swc`` of ``folder`` (default :data:`NEURON_DIR`); the SWC through
    :func:`skelcore.io.load_curve`, so its radii are kept."""
    from ..io import load_curve

    base = Path(folder) if folder is not None else NEURON_DIR
    mesh = read_obj_mesh(base / f"{name}.obj")
    swc = base / f"{name}.swc"
    curve = load_curve(swc)
    if curve.radius is None or not np.all(np.isfinite(curve.radius)):
        from ..errors import SkelInputError

        raise SkelInputError("every traced node needs a radius > 0", swc)
    ids = np.loadtxt(swc, comments="#", usecols=0, ndmin=1)[curve.vertex_map].astype(np.int64)
    return Neuron(name, mesh, curve, ids)


def _face_normals(mesh: TriangleMesh) -> tuple[np.ndarray, np.ndarray]:
    """Unit normals, turned outward when the signed volume says the faces wind inward, and areas."""
    t = mesh.triangles()
    cross = np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])
    double_area = np.linalg.norm(cross, axis=1)
    volume = float(np.einsum("ij,ij->", t[:, 0], cross)) / 6.0
    normals = cross / np.maximum(double_area, 1e-300)[:, None]
    return (normals if volume >= 0 else -normals), double_area / 2.0


class MeshSampler:
    """Uniform samples of a mesh's surface with the interface of :class:`.surface_sampling.SurfaceSampler`
    (``sample(n, rng)``, ``area``), the local radius of a sample being its nearest SWC node's."""

    def __init__(self, mesh: TriangleMesh, nodes: np.ndarray, node_radius: np.ndarray) -> None:
        self.mesh = mesh
        self.normals, self.areas = _face_normals(mesh)
        self.area = float(self.areas.sum())
        self._p = self.areas / self.area
        self._tree = cKDTree(np.asarray(nodes, float))
        self._radius = np.asarray(node_radius, float)

    def sample(self, n: int, rng: np.random.Generator) -> SurfacePoints:
        """Exactly ``n`` points, i.i.d. uniform on the surface (so in random order)."""
        face = rng.choice(len(self._p), size=n, p=self._p)
        u, v = rng.uniform(0.0, 1.0, n), rng.uniform(0.0, 1.0, n)
        fold = u + v > 1.0
        u[fold], v[fold] = 1.0 - u[fold], 1.0 - v[fold]
        t = self.mesh.vertices[self.mesh.faces[face]]
        pts = t[:, 0] + u[:, None] * (t[:, 1] - t[:, 0]) + v[:, None] * (t[:, 2] - t[:, 0])
        _, near = self._tree.query(pts, k=1, workers=-1)
        return SurfacePoints(pts, self.normals[face], self._radius[near])


def _solid_angles(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Signed solid angle of triangle (a, b, c) seen from p, row by row (Van Oosterom and Strackee)."""
    a, b, c = a - p, b - p, c - p
    la, lb, lc = (np.sqrt(np.einsum("ij,ij->i", x, x)) for x in (a, b, c))
    det = np.einsum("ij,ij->i", a, np.cross(b, c))
    den = la * lb * lc + np.einsum("ij,ij->i", a, b) * lc + np.einsum("ij,ij->i", b, c) * la \
        + np.einsum("ij,ij->i", c, a) * lb
    return 2.0 * np.arctan2(det, den)


def _clusters(tri: np.ndarray, size: int) -> tuple[np.ndarray, np.ndarray]:
    """Triangles in Morton order of their centroids, cut into runs of ``size``: (order, run starts)."""
    cen = tri.mean(axis=1)
    lo, span = cen.min(axis=0), max(float(np.ptp(cen, axis=0).max()), 1e-300)
    q = np.minimum((cen - lo) / span * 1024, 1023).astype(np.int64)
    code = np.zeros(len(tri), np.int64)
    for bit in range(10):
        for axis in range(3):
            code |= ((q[:, axis] >> bit) & 1) << (3 * bit + axis)
    return np.argsort(code, kind="stable"), np.arange(0, len(tri), size)


def winding_numbers(mesh: TriangleMesh, points: np.ndarray, *, far: float = 2.0, exact: bool = False,
                    size: int = 8) -> np.ndarray:
    """The generalized winding number of the mesh at each point: the sum of the triangles' signed
    solid angles over 4 pi; about 1 inside, 0 outside, fractional near a hole. Fast (Barill et al.
    2018, first order): triangles are grouped in runs of ``size`` along a Morton curve, and a group
    farther than ``far`` times its radius from the point counts as one dipole (its area-weighted
    normal); the others are summed exactly, in chunks of bounded size (docs/benchmark.md, the real
    suite). ``exact``: every triangle exactly."""
    pts = np.asarray(points, float).reshape(-1, 3)
    tri = mesh.triangles()
    out = np.zeros(len(pts))
    if exact:
        order, starts = np.arange(len(tri)), np.array([0])
        near_p, near_c = np.repeat(np.arange(len(pts)), 1), np.zeros(len(pts), np.int64)
    else:
        order, starts = _clusters(tri, size)
    tri = tri[order]
    counts = np.diff(np.append(starts, len(tri)))
    if not exact:
        cluster = np.repeat(np.arange(len(starts)), counts)
        half_cross = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]) / 2.0
        area = np.linalg.norm(half_cross, axis=1)
        w_area = np.bincount(cluster, weights=area, minlength=len(starts))
        centre = np.column_stack([np.bincount(cluster, weights=area * tri[:, :, i].mean(axis=1),
                                              minlength=len(starts)) for i in range(3)])
        centre /= np.maximum(w_area, 1e-300)[:, None]
        normal = np.column_stack([np.bincount(cluster, weights=half_cross[:, i], minlength=len(starts)) for i in range(3)])
        reach = np.zeros(len(starts))
        np.maximum.at(reach, cluster, np.linalg.norm(tri - centre[cluster][:, None, :], axis=2).max(axis=1))
        near_p, near_c = [], []
        step = max(1, _CHUNK // max(len(starts), 1))
        for s in range(0, len(pts), step):
            d = centre[None, :, :] - pts[s:s + step, None, :]
            dist = np.sqrt(np.einsum("pci,pci->pc", d, d))
            is_far = dist > far * reach[None, :]
            dipole = np.einsum("pci,ci->pc", d, normal) / np.maximum(dist, 1e-300) ** 3
            out[s:s + step] += np.where(is_far, dipole, 0.0).sum(axis=1)
            pi, ci = np.nonzero(~is_far)
            near_p.append(pi + s)
            near_c.append(ci)
        near_p, near_c = np.concatenate(near_p), np.concatenate(near_c)
    # the near groups' triangles, exactly, in chunks of about _CHUNK pairs
    per_pair = counts[near_c]
    bounds = np.searchsorted(np.cumsum(per_pair), np.arange(_CHUNK, int(per_pair.sum()) + _CHUNK, _CHUNK))
    lo = 0
    for hi in np.unique(np.append(bounds + 1, len(near_p))):
        hi = int(min(hi, len(near_p)))
        if hi <= lo:
            continue
        pp, cc = near_p[lo:hi], near_c[lo:hi]
        k = counts[cc]
        rows = np.repeat(pp, k)
        first = np.repeat(starts[cc] - np.cumsum(k) + k, k) + np.arange(int(k.sum()))
        ang = _solid_angles(pts[rows], tri[first, 0], tri[first, 1], tri[first, 2])
        out += np.bincount(rows, weights=ang, minlength=len(pts))
        lo = hi
    return _oriented(mesh, out / (4.0 * np.pi))


def _oriented(mesh: TriangleMesh, w: np.ndarray) -> np.ndarray:
    """Winding numbers of an inward-wound mesh made positive inside."""
    t = mesh.triangles()
    volume = float(np.einsum("ij,ij->", t[:, 0], np.cross(t[:, 1] - t[:, 0], t[:, 2] - t[:, 0])))
    return w if volume >= 0 else -w


def inside_mesh(mesh: TriangleMesh, points: np.ndarray) -> np.ndarray:
    """True where the winding number exceeds 1/2 (inside the surface)."""
    return winding_numbers(mesh, points) > 0.5


def _point_triangle(p: np.ndarray, a: np.ndarray, b: np.ndarray, c: np.ndarray) -> np.ndarray:
    """Distance from each p to the triangle (a, b, c) of its row (closest point by Voronoi regions of
    the triangle, as in Ericson's Real-Time Collision Detection 5.1.5), all arrays K x 3."""
    ab, ac, ap = b - a, c - a, p - a
    d1, d2 = np.einsum("ij,ij->i", ab, ap), np.einsum("ij,ij->i", ac, ap)
    bp = p - b
    d3, d4 = np.einsum("ij,ij->i", ab, bp), np.einsum("ij,ij->i", ac, bp)
    cp = p - c
    d5, d6 = np.einsum("ij,ij->i", ab, cp), np.einsum("ij,ij->i", ac, cp)
    va, vb, vc = d3 * d6 - d5 * d4, d5 * d2 - d1 * d6, d1 * d4 - d3 * d2
    with np.errstate(divide="ignore", invalid="ignore"):
        den = va + vb + vc
        v_in, w_in = vb / den, vc / den
        closest = a + v_in[:, None] * ab + w_in[:, None] * ac  # the face region
        t_bc = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        t_ab = d1 / (d1 - d3)
        t_ac = d2 / (d2 - d6)
    regions = [
        (d1 <= 0) & (d2 <= 0), (d3 >= 0) & (d4 <= d3), (d6 >= 0) & (d5 <= d6),
        (vc <= 0) & (d1 >= 0) & (d3 <= 0), (vb <= 0) & (d2 >= 0) & (d6 <= 0),
        (va <= 0) & ((d4 - d3) >= 0) & ((d5 - d6) >= 0),
    ]
    values = [a, b, c, a + t_ab[:, None] * ab, a + t_ac[:, None] * ac, b + t_bc[:, None] * (c - b)]
    done = np.zeros(len(p), bool)
    for mask, value in zip(regions, values):
        take = mask & ~done
        closest[take] = value[take]
        done |= take
    return np.linalg.norm(p - closest, axis=1)


def surface_distance(mesh: TriangleMesh, points: np.ndarray, k: int = 16) -> np.ndarray:
    """Exact unsigned distance from each point to the mesh's surface: the nearest of the ``k``
    triangles of nearest centroid gives a bound d, then every triangle whose centroid lies within d
    plus the largest centroid-to-corner distance is measured."""
    pts = np.asarray(points, float).reshape(-1, 3)
    tri = mesh.triangles()
    centroid = tri.mean(axis=1)
    reach = float(np.linalg.norm(tri - centroid[:, None, :], axis=2).max())
    tree = cKDTree(centroid)
    k = min(k, len(tri))
    _, cand = tree.query(pts, k=k, workers=-1)
    cand = np.asarray(cand).reshape(len(pts), k)
    rows = np.repeat(np.arange(len(pts)), k)
    d = _point_triangle(pts[rows], *(tri[cand.ravel(), j] for j in range(3))).reshape(len(pts), k).min(axis=1)
    near = tree.query_ball_point(pts, d + reach, workers=-1)
    rows = np.repeat(np.arange(len(pts)), [len(x) for x in near])
    faces = np.concatenate([np.asarray(x, np.int64) for x in near])
    best = d.copy()
    for s in range(0, len(rows), 1 << 20):
        r, f = rows[s:s + (1 << 20)], faces[s:s + (1 << 20)]
        np.minimum.at(best, r, _point_triangle(pts[r], tri[f, 0], tri[f, 1], tri[f, 2]))
    return best


@dataclass(frozen=True)
class NodeFacts:
    """Per SWC node: inside the mesh, its winding number, its distance to the surface (units), how far
    outside it lies (0 when inside; units and node radii), and the mesh's boundary edges."""

    inside: np.ndarray
    winding: np.ndarray
    distance: np.ndarray
    outside_by: np.ndarray
    outside_radii: np.ndarray
    radius: np.ndarray
    boundary_edges: int

    def summary(self) -> dict:
        """The figures docs/benchmark.md quotes: fractions of nodes outside (all, twigs, the rest)."""
        out = ~self.inside
        twig = self.radius < TWIG_RADIUS
        return {"nodes": int(len(out)), "outside": int(out.sum()), "outside_fraction": round(float(out.mean()), 6),
                "twig_nodes": int(twig.sum()),
                "twig_outside_fraction": round(float(out[twig].mean()), 6) if twig.any() else None,
                "outside_by_radii_median": round(float(np.median(self.outside_radii[out])), 6) if out.any() else 0.0,
                "boundary_edges": self.boundary_edges, "closed": self.boundary_edges == 0}


def node_facts(neuron: Neuron) -> NodeFacts:
    """The facts of every node of ``neuron``'s traced skeleton against its mesh (module docstring)."""
    nodes, radius = neuron.skeleton.vertices, np.asarray(neuron.skeleton.radius, float)
    w = winding_numbers(neuron.mesh, nodes)
    inside = w > 0.5
    dist = surface_distance(neuron.mesh, nodes)
    out_by = np.where(inside, 0.0, dist)
    return NodeFacts(inside, w, dist, out_by, out_by / radius, radius, neuron.mesh.boundary_edges())


def write_facts_csv(path: str | os.PathLike, neuron: Neuron, facts: NodeFacts) -> None:
    """``{ID}_gt_facts.csv``: one row per vertex of the reference (its order), columns documented in
    docs/benchmark.md."""
    from ..io.atomic import atomic_open

    with atomic_open(path, "w") as fh:
        fh.write("vertex,swc_id,x,y,z,radius,inside,winding,surface_distance,outside_by,outside_by_radii\n")
        v = neuron.skeleton.vertices
        for i in range(len(v)):
            fh.write(f"{i},{int(neuron.node_ids[i])},{v[i, 0]:.6g},{v[i, 1]:.6g},{v[i, 2]:.6g},{facts.radius[i]:.6g},"
                     f"{int(facts.inside[i])},{facts.winding[i]:.6f},{facts.distance[i]:.6g},"
                     f"{facts.outside_by[i]:.6g},{facts.outside_radii[i]:.6g}\n")


def read_outside_radii(path: str | os.PathLike, n_vertices: int | None = None) -> np.ndarray:
    """The ``outside_by_radii`` column of a facts file (:func:`write_facts_csv`), in its ``vertex``
    order: how far each reference vertex lies outside the mesh, in its radii (0 inside). One-line
    SkelInputError naming the file when it is unreadable, lacks the column or has another vertex count."""
    from ..errors import SkelInputError

    try:
        with open(path, encoding="utf-8") as fh:
            header = fh.readline().strip().split(",")
            data = np.loadtxt(fh, delimiter=",", ndmin=2)
    except OSError as exc:
        raise SkelInputError(f"cannot read the facts file ({exc.strerror or 'unreadable'})", path) from None
    except (ValueError, UnicodeDecodeError):
        raise SkelInputError("not a facts file (a header line, then numbers separated by commas)", path) from None
    if "vertex" not in header or "outside_by_radii" not in header or data.shape[1] != len(header):
        raise SkelInputError("not a facts file (needs the columns vertex and outside_by_radii)", path)
    vertex = data[:, header.index("vertex")].astype(np.int64)
    if n_vertices is not None and len(vertex) != n_vertices:
        raise SkelInputError(f"the facts have {len(vertex)} rows for a reference of {n_vertices} vertices", path)
    if not np.array_equal(np.sort(vertex), np.arange(len(vertex))):
        raise SkelInputError("the facts' vertex column must number the rows 0..n-1", path)
    out = np.empty(len(vertex))
    out[vertex] = data[:, header.index("outside_by_radii")]
    if not (np.all(np.isfinite(out)) and np.all(out >= 0)):
        raise SkelInputError("outside_by_radii must be finite and >= 0", path)
    return out
