"""Shared helpers of the diagnostics tests: a shape's normalized cloud and curve, its curve samples
and their boundedness (the values the evaluation passes to the diagnostics)."""

from __future__ import annotations

import numpy as np

from skelcore import Params
from skelcore.curve import CurveSkeleton
from skelcore.metrics.curve_sampling import sample_curve
from skelcore.geometry import Normalization
from skelcore.metrics.boundedness import boundedness


def normalized(cloud: np.ndarray, verts: np.ndarray, edges: np.ndarray, params: Params = Params()):
    """(normalized cloud, normalized curve, curve samples, their boundedness)."""
    norm = Normalization.from_cloud(cloud, params.normalize_by, params.normalized_size)
    c = norm.apply(cloud)
    curve = CurveSkeleton.from_raw(norm.apply(verts), edges)
    samples = sample_curve(curve, params.curve_samples, collinear_cos=params.collinear_cos)
    return c, curve, samples, boundedness(c, samples.points, params=params)


def attach_path(verts: np.ndarray, edges: np.ndarray, start: int, end_point: np.ndarray, pieces: int,
                to: int | None = None) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """A path of ``pieces`` edges from vertex ``start`` to ``end_point`` (or on to vertex ``to``):
    (vertices, edges, ids of the new vertices)."""
    a = verts[start]
    pts = a + np.linspace(0, 1, pieces + 1)[1:, None] * (np.asarray(end_point) - a)
    if to is not None:
        pts = pts[:-1]
    ids = np.arange(len(verts), len(verts) + len(pts))
    chain = np.concatenate([[start], ids] + ([[to]] if to is not None else []))
    return np.vstack([verts, pts]), np.vstack([edges, np.column_stack([chain[:-1], chain[1:]])]), ids


def sparse_half(sampler, n: int, rng: np.random.Generator, first: np.ndarray | None = None) -> np.ndarray:
    """``n`` points of ``sampler`` (a SurfaceSampler) whose half beyond the median of the longest side
    keeps a tenth of its points: ``first`` (or a fresh sample) thinned, then further samples thinned
    alike until ``n`` are kept."""
    pts = sampler.sample(n, rng).points if first is None else first
    axis = int(np.argmax(np.ptp(pts, axis=0)))
    median = float(np.median(pts[:, axis]))
    parts, have = [], 0
    while have < n:
        keep = (pts[:, axis] < median) | (rng.uniform(size=len(pts)) < 0.1)
        parts.append(pts[keep])
        have += int(keep.sum())
        pts = sampler.sample(n, rng).points
    return np.vstack(parts)[:n]


def traced_crop(neuron, centre_node: int, radius: float, points: int, seed: int = 0):
    """A shipped traced neuron (``skelcore.benchmark.neurons.load_neuron``) cut to a ball of ``radius``
    around its node ``centre_node``: (the cloud of ``points`` samples of the whole mesh inside the ball,
    the traced vertices and edges inside it, each kept vertex's old index as a map old -> new (-1 when
    dropped), the kept vertices' traced radii)."""
    from skelcore.benchmark.neurons import MeshSampler

    sk = neuron.skeleton
    at = {int(i): k for k, i in enumerate(neuron.node_ids)}
    centre = sk.vertices[at[int(centre_node)]]
    cloud = MeshSampler(neuron.mesh, sk.vertices, np.asarray(sk.radius, float)).sample(
        points, np.random.default_rng(seed)).points
    cloud = cloud[np.linalg.norm(cloud - centre, axis=1) <= radius]
    keep = np.linalg.norm(sk.vertices - centre, axis=1) <= radius
    e = sk.edges[keep[sk.edges].all(axis=1)]
    used = np.unique(e)
    remap = np.full(len(sk.vertices), -1)
    remap[used] = np.arange(len(used))
    return cloud, sk.vertices[used], remap[e], remap, np.asarray(sk.radius)[used]
