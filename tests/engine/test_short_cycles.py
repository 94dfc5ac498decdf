"""The incremental short-cycle search of the curve extraction (skelcore/skeleton/curve_extraction.py
``_ShortCycles``) returns, after every collapse, the cycle a scan from scratch returns first: on random
graphs (lattice positions, so lengths tie), on the bundled samples' curves and on a traced neuron's.
The scan from scratch is kept here as the reference (the extraction's former loop, each edge's
shortest path asked of the same Dijkstra)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from skelcore.skeleton import SkeletonizeParams, skeletonize
from skelcore.skeleton import curve_extraction as ce

SAMPLES = Path(__file__).resolve().parents[2] / "resources" / "samples"


def _reference_cycle(g, max_length):
    """The first cycle of the scan from scratch: every alive a, every neighbour b > a, in order."""
    if max_length <= 0:
        return None
    for a in np.flatnonzero(g.alive):
        a = int(a)
        for b in sorted(g.adj[a]):
            if b > a:
                path = ce._shortest_path(g, a, b, max_length - math.dist(g.pos(a), g.pos(b)))
                if path is not None:
                    return path
    return None


class _Checked(ce._ShortCycles):
    """The incremental search, compared with the reference on the same graph at every call."""

    calls: list[bool] = []

    def find(self):
        want = _reference_cycle(self.g, self.max_length)
        got = super().find()
        assert got == want
        _Checked.calls.append(got is not None)
        return got


@pytest.fixture
def checked(monkeypatch):
    monkeypatch.setattr(ce, "_ShortCycles", _Checked)
    _Checked.calls = []
    return _Checked.calls


def _graph(pos, edges):
    pos = np.asarray(pos, float).reshape(-1, 3)
    return ce._Graph(pos, np.ones(len(pos)), np.asarray(edges, np.int64).reshape(-1, 2))


@settings(max_examples=150, deadline=None)
@given(
    n=st.integers(3, 40),
    data=st.data(),
    max_length=st.sampled_from([0.0, 2.5, 4.0, 6.0, 12.0]),
)
def test_random_graphs_give_the_scans_cycles(n, data, max_length):
    pos = data.draw(st.lists(st.tuples(*[st.integers(0, 3)] * 3), min_size=n, max_size=n))
    pairs = [(a, b) for a in range(n) for b in range(a + 1, n)]
    edges = data.draw(st.lists(st.sampled_from(pairs), max_size=3 * n))
    g = _graph(pos, edges)
    calls = []
    _Checked.calls = calls
    saved, ce._ShortCycles = ce._ShortCycles, _Checked
    try:
        ce._collapse_triangles(g, lambda _s, _f: None)
        ce._collapse_short_cycles(g, max_length, lambda _s, _f: None)
    finally:
        ce._ShortCycles = saved
    assert calls and not calls[-1]
    assert _reference_cycle(g, max_length) is None


def test_a_ladder_collapses_rung_by_rung(checked):
    # two rails of 12 vertices joined by rungs: every square is a short cycle, found again each time
    k = 12
    pos = [(i, 0, 0) for i in range(k)] + [(i, 1.5, 0) for i in range(k)]
    edges = [(i, i + 1) for i in range(k - 1)] + [(k + i, k + i + 1) for i in range(k - 1)] + [(i, k + i) for i in range(k)]
    g = _graph(pos, edges)
    ce._collapse_short_cycles(g, 6.0, lambda _s, _f: None)
    assert sum(checked) >= 5 and not checked[-1]
    assert _reference_cycle(g, 6.0) is None


def test_a_search_that_found_nothing_is_asked_again_after_a_collapse_nearby(checked):
    # edge (0, 6) closes no cycle shorter than 9.14 at first; after the collapses of the cycle 4-2-5-1
    # (found at edge (1, 4)) it closes 6-2-7-0, below the scan's frontier: only asking it again finds
    # that cycle first
    pos = [[4.36, 3.01, 3.8], [2.63, 3.61, 5.39], [2.41, 4.62, 3.16], [1.87, 5.16, 4.11],
           [1.42, 4.93, 5.78], [2.37, 3.25, 3.56], [4.18, 4.29, 2.41], [3.89, 2.11, 3.13]]
    edges = [[0, 6], [0, 7], [1, 4], [1, 5], [2, 3], [2, 5], [2, 6], [3, 4], [3, 5], [5, 7]]
    g = _graph(pos, edges)
    ce._collapse_triangles(g, lambda _s, _f: None)
    ce._collapse_short_cycles(g, 9.14, lambda _s, _f: None)
    assert sum(checked) >= 2 and not checked[-1]


@pytest.mark.parametrize("name", ["cylinder", "torus", "yshape"])
def test_the_bundled_samples_curves(checked, name):
    from skelcore.io import load_cloud

    skeletonize(load_cloud(SAMPLES / f"{name}_cloud.ply"), SkeletonizeParams())
    assert checked and not checked[-1]


def test_a_traced_neurons_curve(checked):
    from skelcore.benchmark.neurons import MeshSampler, load_neuron

    neuron = load_neuron("1734350788")
    sk = neuron.skeleton
    cloud = MeshSampler(neuron.mesh, sk.vertices, np.asarray(sk.radius, float)).sample(
        6000, np.random.default_rng(0)).points
    skeletonize(cloud, SkeletonizeParams())
    assert sum(checked) >= 3 and not checked[-1]
