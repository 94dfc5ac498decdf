"""The rays kernel's far rays (docs/boundedness.md 3.10-3.11) against an exhaustive ray test of every point:
whatever prunes or orders the walks (packets' lane groups with no open ray, the walk up from a hint, hints
skipped, always tried or asked of memory ahead, lone queries cast one by one or a block at a time band by
band), a sample is hit iff some point beyond the cut passes the kernel's float32 ball test."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore.metrics import rays_kernel
from skelcore.metrics.boundedness import rays_radius
from skelcore.metrics.rays_kernel import BallTree
from skelcore.shapes import torus

ROWS, BINS = 48, 96


def _directions() -> np.ndarray:
    """The raster's sample directions as the kernel casts them: float32 of s_j cos(lon_k), s_j sin(lon_k), z_j."""
    z = -1.0 + (np.arange(ROWS) + 0.5) * (2.0 / ROWS)
    s = np.sqrt(1.0 - z * z)
    lon = (np.arange(BINS) + 0.5) * (2.0 * np.pi / BINS)
    return np.stack([(s[:, None] * np.cos(lon)[None, :]).astype(np.float32),
                     (s[:, None] * np.sin(lon)[None, :]).astype(np.float32),
                     np.repeat(z.astype(np.float32)[:, None], BINS, axis=1)], axis=-1).reshape(-1, 3)


def _exhaustive_beta(points: np.ndarray, origins: np.ndarray, h: float) -> np.ndarray:
    """Share of samples whose ray from the (float32) origin meets a ball of radius h around a point with
    |p - o|^2 > h^2: the kernel's point test (float32, the same operations in the same order) on every point."""
    s = _directions()
    hf = np.float32(h)
    h2 = hf * hf
    out = np.empty(len(origins))
    for i, o in enumerate(origins.astype(np.float32)):
        w = points - o
        d2 = w[:, 0] * w[:, 0] + w[:, 1] * w[:, 1] + w[:, 2] * w[:, 2]
        keep = d2 > h2
        w, d2 = w[keep], d2[keep]
        tt = np.outer(s[:, 0], w[:, 0]) + np.outer(s[:, 1], w[:, 1])
        tt += np.outer(s[:, 2], w[:, 2])
        hit = (tt > 0) & (d2[None, :] - tt * tt <= h2)
        out[i] = np.count_nonzero(hit.any(axis=1)) / len(s)
    return out


def _builds() -> list:
    """The kernel's builds this machine runs: the generic one, and the AVX2 one where the CPU has it."""
    from skelcore.metrics import _raycast

    modules = [_raycast]
    if _raycast.cpu_has_avx2():
        try:
            from skelcore.metrics import _raycast_avx2

            modules.append(_raycast_avx2)
        except ImportError:
            pass
    return modules


@pytest.fixture(scope="module")
def case():
    shape = torus(1200, 1.0, 0.3, n_curve=32, seed=4)
    rng = np.random.default_rng(4)
    tree = BallTree(shape.cloud)
    h = rays_radius(shape.cloud)
    # an arc of the core circle in steps of 1.5 h (within the two reaches that keep the hints, so each
    # ray also tries the hint its sample's moved hit suggests), an arc off the core, and scattered queries
    angle = np.arange(24) * 1.5 * h
    arc = np.column_stack([np.cos(angle), np.sin(angle), np.zeros_like(angle)])
    queries = np.vstack([arc, arc * 1.15 + [0.0, 0.0, 0.1], rng.uniform(-1.4, 1.4, (10, 3)), [[0.0, 0.0, 0.0]]])
    queries = np.ascontiguousarray(queries, np.float64)
    return tree, queries, h, _exhaustive_beta(tree.points, queries, h)


def _no_seeds(block: int) -> tuple:
    """The kernel's optional arguments after the hint policy: no seed tables, none kept, ``block`` lone
    queries cast together (0: one by one; -1: the kernel's BLOCK where the points exceed BLOCK_FROM bytes,
    else one by one, as for this small torus)."""
    none = np.zeros(0, np.int32)
    return (none, np.zeros(0), none, none, none, block)


@pytest.mark.parametrize("policy", [(), (0, 0), (1001, 10**6), (250, 7, 0), (-1, -1, -1, *_no_seeds(32)),
                                    (-1, -1, -1, *_no_seeds(5)), (0, 0, 0, *_no_seeds(7))],
                         ids=["default", "hints-always", "hints-never", "hints-prefetched", "blocks-of-32", "blocks-of-5",
                              "blocks-of-7-hints-always-prefetched"])
def test_far_rays_hit_exactly_where_some_point_passes_the_ball_test(case, policy):
    """Clusters of one query at its own position with reach h: no near caps, every sample a far ray; each
    build's beta equals the exhaustive test's bit for bit (a lane group skipped with an open ray, or a
    walk cut short, would lose hits); "hints-prefetched" asks memory for the hints of every tile, as for
    a cloud beyond the kernel's PREFETCH_FROM bytes (docs/boundedness.md 3.17); lone queries are cast one
    by one here by default (the torus is below BLOCK_FROM bytes), and in blocks band by band (BLOCK, 3.19),
    of 32 as for a larger cloud and of 5 and 7 that end inside the arcs of queries."""
    modules = _builds()
    tree, queries, h, ref = case
    n = len(queries)
    assert 0.05 < float(np.mean(ref > 0.9)) < 0.95  # bounded and open queries both present
    for module in modules:
        beta, stats = np.zeros(n), np.zeros(6, np.int64)
        module.clusters(tree.points, tree.nodes, tree.leaves, queries, np.arange(n + 1, dtype=np.int64), queries,
                        np.full(n, h), 0, n, float(h), ROWS, BINS, beta, stats, np.zeros(1, np.int32),
                        np.zeros(1, np.int64), *policy)
        assert stats[1] == 0 and stats[2] > 0.9 * n * ROWS * BINS  # no near caps: the far rays decide
        assert np.array_equal(beta, ref), module.__name__


def test_the_kernel_in_use_is_one_of_the_two_builds():
    from skelcore.metrics import _raycast

    assert rays_kernel._raycast.__name__.rsplit(".", 1)[-1] in ("_raycast", "_raycast_avx2")
    assert _raycast.LEAF_SIZE == rays_kernel.LEAF_SIZE


@pytest.mark.parametrize("block", [32, 0, 5], ids=["blocks-of-32", "one-by-one", "blocks-of-5"])
@pytest.mark.parametrize("seeds", ["kept", "garbage"])
def test_far_rays_seeded_from_kept_tables_hit_exactly_as_the_ball_test(case, seeds, block):
    """Each cluster starting from a hint table (docs/boundedness.md 3.18): the tables one pass kept of the
    queries shifted by half a step (the moved hints then read the seeds' origins), or tables of random
    indices (inner nodes and rows out of range among them, which the kernel must drop, not walk): beta
    equals the exhaustive test's bit for bit on both builds, lone queries cast in blocks or one by one (3.19)."""
    modules = _builds()
    tree, queries, h, ref = case
    n, table = len(queries), 2 * ROWS * BINS
    origins = np.ascontiguousarray(queries + [0.75 * h, 0.0, 0.0])
    rng = np.random.default_rng(7)
    for module in modules:
        if seeds == "kept":
            tables = np.full((n, table), -1, np.int32)
            module.clusters(tree.points, tree.nodes, tree.leaves, origins, np.arange(n + 1, dtype=np.int64), origins,
                            np.full(n, h), 0, n, float(h), ROWS, BINS, np.zeros(n), np.zeros(6, np.int64),
                            np.zeros(1, np.int32), np.zeros(1, np.int64), -1, -1, -1, np.zeros(0, np.int32),
                            np.zeros(0), np.zeros(0, np.int32), tables, np.arange(n, dtype=np.int32), block)
            assert (tables[:, 1::2] >= 0).mean() > 0.3  # the pass kept its hits
        else:
            tables = rng.integers(-5, len(tree.nodes) + len(tree.points) + 5, (n, table)).astype(np.int32)
        beta, stats = np.zeros(n), np.zeros(6, np.int64)
        module.clusters(tree.points, tree.nodes, tree.leaves, queries, np.arange(n + 1, dtype=np.int64), queries,
                        np.full(n, h), 0, n, float(h), ROWS, BINS, beta, stats, np.zeros(1, np.int32),
                        np.zeros(1, np.int64), 0 if seeds == "garbage" else -1, -1, -1, tables, origins,
                        np.arange(n, dtype=np.int32), np.zeros(0, np.int32), np.zeros(0, np.int32), block)
        assert stats[4] > 0  # the hints were tried
        assert np.array_equal(beta, ref), module.__name__


@pytest.mark.parametrize("policy", [(-1, -1), (1001, 10**6), (0, 0)], ids=["default", "hints-never", "hints-always"])
@pytest.mark.parametrize("block", [0, 32, 5], ids=["one-by-one", "blocks-of-32", "blocks-of-5"])
def test_far_rays_of_packets_on_the_wide_tree_hit_exactly_as_the_ball_test(case, policy, block):
    """The packets walking the tree with 8 (AVX2) or 4 children a node (``BallTree.wide``, docs/boundedness.md 3.21):
    beta equals the exhaustive test's bit for bit on both builds, with the hints as the kernel chooses, never
    (every ray in a packet) and always, lone queries one by one and in blocks."""
    tree, queries, h, ref = case
    n = len(queries)
    for module in _builds():
        assert len(tree.wide(module)) > 0
        beta, stats = np.zeros(n), np.zeros(6, np.int64)
        module.clusters(tree.points, tree.nodes, tree.leaves, queries, np.arange(n + 1, dtype=np.int64), queries,
                        np.full(n, h), 0, n, float(h), ROWS, BINS, beta, stats, np.zeros(1, np.int32),
                        np.zeros(1, np.int64), *policy, 0, *_no_seeds(block), tree.wide(module))
        assert np.array_equal(beta, ref), module.__name__


def test_a_wide_tree_of_other_nodes_is_refused(case):
    """The kernel follows the wide tree's indices: one made for another tree (here a smaller one) is refused
    before any ray is cast, as is one off its 64-byte line and, where both builds run, the other build's."""
    tree, queries, h, _ = case
    other = BallTree(tree.points[:300].astype(np.float64) * 2.0)
    n = len(queries)
    for module in _builds():
        for wide in (other.wide(module), tree.wide(module)[1:]):
            with pytest.raises(ValueError, match="wide tree"):
                module.clusters(tree.points, tree.nodes, tree.leaves, queries, np.arange(n + 1, dtype=np.int64),
                                queries, np.full(n, h), 0, n, float(h), ROWS, BINS, np.zeros(n), np.zeros(6, np.int64),
                                np.zeros(1, np.int32), np.zeros(1, np.int64), -1, -1, 0, *_no_seeds(0), wide)
    builds = _builds()
    if len(builds) == 2 and builds[0].WIDE_BYTES != builds[1].WIDE_BYTES:
        with pytest.raises(ValueError, match="wide tree"):
            builds[0].clusters(tree.points, tree.nodes, tree.leaves, queries, np.arange(n + 1, dtype=np.int64),
                               queries, np.full(n, h), 0, n, float(h), ROWS, BINS, np.zeros(n), np.zeros(6, np.int64),
                               np.zeros(1, np.int32), np.zeros(1, np.int64), -1, -1, 0, *_no_seeds(0),
                               tree.wide(builds[1]))
