"""Branches and the cycle basis of a curve skeleton (skelcore/diagnostics/branches.py)."""

from __future__ import annotations

import networkx as nx
import numpy as np
import pytest

from skelcore import CurveSkeleton, shapes
from skelcore.metrics.curve_sampling import sample_curve
from skelcore.diagnostics import JUNCTION, decompose_branches


def _curve(shape) -> CurveSkeleton:
    return CurveSkeleton.from_raw(shape.curve_vertices, shape.curve_edges)


def _check_partition(curve: CurveSkeleton, b) -> None:
    """Every edge lies on exactly one branch, as a step of that branch's path."""
    seen = np.zeros(curve.n_edges, int)
    key = {tuple(e): i for i, e in enumerate(curve.edges.tolist())}
    for i, p in enumerate(b.paths):
        for x, y in zip(p[:-1], p[1:]):
            e = key[(min(x, y), max(x, y))]
            seen[e] += 1
            assert b.edge_branch[e] == i
    assert np.all(seen == 1)
    deg = curve.degrees()
    for i, p in enumerate(b.paths):
        if b.kind[i] == "point":
            continue
        assert np.all(deg[p[1:-1]] == 2)  # inner vertices have degree 2
        if b.kind[i] != "cycle":
            assert deg[p[0]] != 2 and deg[p[-1]] != 2


def test_y_has_three_terminal_branches_and_a_junction():
    s = shapes.y_shape(n=3000)
    curve = _curve(s)
    samples = sample_curve(curve, 200)
    b = decompose_branches(curve, cloud=s.cloud, sample_edge=samples.edge)
    assert b.kind == ["terminal"] * 3
    assert np.allclose(b.length, 2.0)
    assert sorted(map(sorted, b.end_degrees.tolist())) == [[1, 3]] * 3
    assert np.flatnonzero(b.vertex_branch == JUNCTION).tolist() == [0]
    assert np.array_equal(b.sample_branch, b.edge_branch[samples.edge])
    assert b.cycle_rank == 0 and b.n_components == 1
    # the local radius along each arm is the arm's radius (0.25), away from the junction and ends
    assert np.allclose(b.radius_median, 0.25, atol=0.01)
    _check_partition(curve, b)


def test_t_branches_carry_their_own_radius():
    s = shapes.t_shape(n=6000, bar_radius=0.3, stem_radius=0.15)
    b = decompose_branches(_curve(s), cloud=s.cloud)
    stem = [i for i, p in enumerate(b.paths) if s.curve_vertices[p][:, 2].min() < -1]
    assert len(stem) == 1
    assert b.radius_median[stem[0]] == pytest.approx(0.15, abs=0.01)
    others = [i for i in range(3) if i != stem[0]]
    assert np.allclose(b.radius_median[others], 0.3, atol=0.01)


def test_torus_core_is_one_cycle_branch():
    s = shapes.torus(n=2000, n_curve=32)
    curve = _curve(s)
    b = decompose_branches(curve)
    assert b.kind == ["cycle"] and b.cycle_rank == 1
    poly = b.cycle_polygon(0)
    assert sorted(poly.tolist()) == list(range(32))
    assert b.length[0] == pytest.approx(curve.edge_lengths().sum())
    assert np.all(np.isnan(b.radius_median))  # no cloud given


def test_figure_eight_has_two_loops_at_one_vertex():
    s = shapes.genus2(n=2000)
    b = decompose_branches(_curve(s))
    assert b.kind == ["loop", "loop"] and b.cycle_rank == 2
    assert b.end_degrees.tolist() == [[4, 4], [4, 4]]


def test_points_paths_and_mixed_components():
    # an isolated vertex, an isolated edge, a triangle with a tail, and a theta graph
    v = np.random.default_rng(0).normal(size=(14, 3))
    e = [(1, 2), (3, 4), (4, 5), (5, 3), (5, 6), (7, 8), (8, 9), (9, 10), (10, 7), (7, 11), (11, 12), (12, 9)]
    curve = CurveSkeleton.from_raw(v, e)
    b = decompose_branches(curve)
    kinds = sorted(b.kind)
    assert kinds.count("point") == 2  # vertices 0 and 13
    assert kinds.count("path") == 1
    assert b.cycle_rank == curve.n_edges - curve.n_vertices + b.n_components == 3
    _check_partition(curve, b)


def _random_graph(rng: np.random.Generator, n: int, extra: int) -> CurveSkeleton:
    """A random tree of n vertices, subdivided, plus ``extra`` chords."""
    parent = [int(rng.integers(0, i)) for i in range(1, n)]
    e = [(p, i) for i, p in enumerate(parent, start=1)]
    for _ in range(extra):
        a, c = rng.choice(n, 2, replace=False)
        e.append((int(a), int(c)))
    v = rng.normal(size=(n, 3))
    return CurveSkeleton.from_raw(v, e)


@pytest.mark.parametrize("seed", range(8))
def test_random_graphs_partition_and_minimum_cycle_basis(seed):
    """Against networkx: the cycle basis has the cycle rank, its cycles are closed walks of the
    graph, independent over GF(2), and as short in total as networkx's minimum cycle basis."""
    rng = np.random.default_rng(seed)
    curve = _random_graph(rng, 30, int(rng.integers(0, 8)))
    b = decompose_branches(curve)
    _check_partition(curve, b)
    g = nx.Graph()
    g.add_nodes_from(range(curve.n_vertices))
    w = curve.edge_lengths()
    for (x, y), le in zip(curve.edges.tolist(), w):
        g.add_edge(x, y, weight=le)
    assert b.cycle_rank == len(nx.cycle_basis(g))
    rows = []
    for i in range(b.cycle_rank):
        poly = b.cycle_polygon(i)
        for x, y in zip(poly, np.roll(poly, -1)):
            assert g.has_edge(int(x), int(y))
        row = np.zeros(curve.n_edges, np.uint8)
        row[b.cycle_edges(i)] = 1
        rows.append(row)
    # independent over GF(2)
    m = np.array(rows, np.uint8).reshape(len(rows), curve.n_edges)
    rank, r = 0, m.copy()
    for col in range(r.shape[1]):
        piv = [i for i in range(rank, len(r)) if r[i, col]]
        if not piv:
            continue
        r[[rank, piv[0]]] = r[[piv[0], rank]]
        for i in range(len(r)):
            if i != rank and r[i, col]:
                r[i] ^= r[rank]
        rank += 1
    assert rank == b.cycle_rank
    ours = sum(w[b.cycle_edges(i)].sum() for i in range(b.cycle_rank))
    theirs = sum(sum(g[c[k]][c[(k + 1) % len(c)]]["weight"] for k in range(len(c))) for c in nx.minimum_cycle_basis(g, weight="weight"))
    assert ours == pytest.approx(theirs, rel=1e-9)


def test_to_dict_lists_every_branch():
    s = shapes.tree3(n=2000)
    b = decompose_branches(_curve(s), cloud=s.cloud).flagged("spurious_branches", [2])
    d = b.to_dict()
    assert d["n_branches"] == 7 and d["cycle_rank"] == 0
    assert [x["flags"] for x in d["branches"]][2] == ["spurious_branches"]
    assert all(x["radius"]["median"] > 0 for x in d["branches"])
    assert sorted(x["kind"] for x in d["branches"]).count("terminal") == 5


def test_large_cycle_space_gets_fundamental_cycles_of_a_minimum_spanning_forest():
    """Beyond 64 cycles: the right count, closed walks, independent over GF(2)."""
    rng = np.random.default_rng(11)
    curve = _random_graph(rng, 120, 90)
    b = decompose_branches(curve)
    assert b.cycle_rank == curve.n_edges - curve.n_vertices + b.n_components > 64
    m = np.zeros((b.cycle_rank, curve.n_edges), np.uint8)
    adj = {tuple(e) for e in curve.edges.tolist()}
    for i in range(b.cycle_rank):
        poly = b.cycle_polygon(i)
        for x, y in zip(poly, np.roll(poly, -1)):
            assert (min(x, y), max(x, y)) in adj
        m[i, b.cycle_edges(i)] = 1
    r, rank = m.copy(), 0
    for col in range(r.shape[1]):
        piv = [i for i in range(rank, len(r)) if r[i, col]]
        if not piv:
            continue
        r[[rank, piv[0]]] = r[[piv[0], rank]]
        rows = np.flatnonzero(r[:, col])
        rows = rows[rows != rank]
        r[rows] ^= r[rank]
        rank += 1
    assert rank == b.cycle_rank


@pytest.mark.parametrize("edges", [np.zeros((0, 2), int), [[0, 1]], [[0, 1], [1, 2]]])
def test_degenerate_curves_run_through_every_diagnostic(edges):
    from skelcore.diagnostics import find_curve_defects

    s = shapes.cylinder(n=1500, seed=1)
    v = np.array([[0, 0, 1.0], [0, 0, 2.0], [0, 0, 3.0]])
    curve = CurveSkeleton.from_raw(v, edges)
    d = find_curve_defects(s.cloud, curve)
    assert len(d.branches) >= 1 and d.cycles.n_cycles == 0 and d.warnings() == []
    assert d.to_dict()["branches"]["n_branches"] == len(d.branches)


def test_kept_branch_paths_are_the_walks_own_and_copies():
    """branch_paths keeps the chains of the last edge sets: a curve with the same edges (other
    vertices) gets the same paths, one more (isolated) vertex or another edge set its own, and the arrays
    handed out are copies (writing to them changes no later answer)."""
    from skelcore.diagnostics import branches as B

    curve = _curve(shapes.y_shape(n=3000))
    want, want_eb = B._chains(curve, curve.degrees())
    got, eb = B.branch_paths(curve)
    assert len(got) == len(want) and all(np.array_equal(a, b) for a, b in zip(got, want))
    assert np.array_equal(eb, want_eb)
    got[0][:] = -7
    eb[:] = -7
    moved = CurveSkeleton.from_raw(curve.vertices + 1.0, curve.edges)
    again, eb2 = B.branch_paths(moved)
    assert all(np.array_equal(a, b) for a, b in zip(again, want)) and np.array_equal(eb2, want_eb)
    extra = CurveSkeleton.from_raw(np.vstack([curve.vertices, [[5.0, 5.0, 5.0]]]), curve.edges)
    with_point, _ = B.branch_paths(extra)
    assert len(with_point) == len(want) + 1 and with_point[-1].tolist() == [curve.n_vertices]
    cut = CurveSkeleton.from_raw(curve.vertices, curve.edges[1:])
    assert len(B.branch_paths(cut)[0]) == len(B._chains(cut, cut.degrees())[0]) != len(want)
    b = decompose_branches(curve)
    assert all(np.array_equal(a, c) for a, c in zip(b.paths, want))
