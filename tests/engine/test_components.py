"""The compiled connected components (skelcore/metrics/components.py) label as scipy's
``connected_components(..., directed=False)``: the same count and the same labels, on random graphs with
isolated nodes, loops, repeated and reversed edges, and on a missing region's link graph."""

import numpy as np
import pytest
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import connected_components
from scipy.spatial import cKDTree

from skelcore.metrics.components import undirected_components


def _scipy(n, a, b):
    return connected_components(coo_matrix((np.ones(len(a)), (a, b)), shape=(n, n)).tocsr(), directed=False)


@pytest.mark.parametrize("seed", range(5))
def test_labels_equal_scipys_on_random_graphs(seed):
    rng = np.random.default_rng(seed)
    for _ in range(60):
        n = int(rng.integers(1, 400))
        m = int(rng.integers(0, 2 * n))
        a, b = rng.integers(0, n, m), rng.integers(0, n, m)
        a[: m // 10] = b[: m // 10]  # loops
        count, labels = undirected_components(n, a, b)
        want_count, want = _scipy(n, a, b)
        assert count == want_count
        assert labels.dtype == want.dtype and np.array_equal(labels, want)


def test_labels_equal_scipys_on_a_link_graph():
    """A tube's points linked to their 8 nearest within a link, as the missing parts link a region:
    one long component (a chain of links), plus stray points each alone."""
    rng = np.random.default_rng(7)
    t = rng.uniform(0, 20, 6000)
    angle = rng.uniform(0, 2 * np.pi, 6000)
    pts = np.column_stack([t, np.cos(angle), np.sin(angle)])
    pts = np.vstack([pts, rng.uniform(30, 60, (50, 3))])[rng.permutation(6050)]
    d, j = cKDTree(pts).query(pts, k=9, distance_upper_bound=0.3)
    ok = np.isfinite(d[:, 1:])
    heads = np.repeat(np.arange(len(pts)), ok.sum(axis=1))
    tails = j[:, 1:][ok]
    count, labels = undirected_components(len(pts), heads, tails)
    want_count, want = _scipy(len(pts), heads, tails)
    assert count == want_count > 1
    assert np.array_equal(labels, want)


def test_no_nodes_and_bad_edges():
    count, labels = undirected_components(0, np.zeros(0, np.int64), np.zeros(0, np.int64))
    assert count == 0 and len(labels) == 0
    assert undirected_components(3, [], [])[0] == 3
    with pytest.raises(ValueError):
        undirected_components(3, [0, 3], [1, 1])
    with pytest.raises(ValueError):
        undirected_components(3, [0], [1, 2])
