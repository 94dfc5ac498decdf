"""The calibration's ``broken`` kind and the truth of ``disconnected`` (docs/diagnostics.md
"Disconnected", "Precision and recall per warning"): the cut, the truth on a reference in one and in
two pieces, a hit only on a piece the cut made, and one small task's rows."""

from __future__ import annotations

import numpy as np

from skelcore.benchmark.calibration.calib_tables import outcome, summary_rows
from skelcore.benchmark.calibration.grid import Task
from skelcore.benchmark.calibration.pieces_truth import cycles_cut, disconnected_truth, n_pieces, reference_split
from skelcore.benchmark.calibration.runner import run_task
from skelcore.benchmark.calibration.skeletons import Made, World
from skelcore.benchmark.calibration.truth import origin
from skelcore.benchmark.skeleton_defects import cut_edges


def _path(n: int, x0: float = 0.0) -> tuple[np.ndarray, np.ndarray]:
    v = np.column_stack([x0 + np.arange(n, dtype=float), np.zeros(n), np.zeros(n)])
    return v, np.column_stack([np.arange(n - 1), np.arange(1, n)])


def _world(v: np.ndarray, e: np.ndarray, parts=None, cloud=None) -> World:
    cloud = v.copy() if cloud is None else cloud
    return World(cloud, np.ones(len(cloud)), (v, e, np.ones(len(v))), lambda p: np.zeros(len(p)), True,
                 None, parts)


def test_the_cut_deletes_inner_edges_and_splits_the_curve():
    v, e = _path(12)
    for seed in range(5):  # a path always splits: 3 pieces, or 2 when the cuts share a vertex (dropped)
        nv, ne = cut_edges(v, e, 2, np.random.default_rng(seed))
        assert len(ne) == len(e) - 2 and n_pieces(nv, ne)[0] == len(nv) - len(ne) >= 2
        assert {0, 11} <= set(origin(Made("broken", nv, ne), v)[np.unique(ne)].tolist())  # the tips keep their edge
    ring = np.column_stack([np.cos(np.linspace(0, 2 * np.pi, 9)[:-1]), np.sin(np.linspace(0, 2 * np.pi, 9)[:-1]),
                            np.zeros(8)])
    re = np.column_stack([np.arange(8), (np.arange(8) + 1) % 8])
    outs = [cut_edges(ring, re, 2, np.random.default_rng(s)) for s in range(20)]
    assert any(o is None for o in outs) and any(o is not None for o in outs)  # adjacent cuts do not split a ring
    assert all(n_pieces(*o)[0] == 2 for o in outs if o is not None)
    cut = next(o for o in outs if o is not None)
    w = _world(ring, re)
    assert cycles_cut(Made("broken", *cut), w) == 1 and cycles_cut(Made("intact", ring, re), w) == 0


def test_disconnected_truth_counts_the_intact_curve_and_leaves_out_a_reference_split():
    v, e = _path(10)
    w = _world(v, e)
    intact = Made("intact", v, e)
    broken = Made("broken", v, np.delete(e, 4, axis=0))
    t = disconnected_truth(intact, w, origin(intact, v), set(), None)
    assert (t["truth_disconnected"], t["curve_pieces"], t["reference_split"]) == (0, 1, False)
    flag = np.zeros(len(v), bool)
    flag[5:] = True  # a piece the cut made
    t = disconnected_truth(broken, w, origin(broken, v), {"disconnected"}, flag)
    assert (t["truth_disconnected"], t["pieces_located"]) == (1, True)
    v2, e2 = _path(5, 20.0)
    two_v, two_e = np.vstack([v, v2]), np.vstack([e, e2 + len(v)])
    assert reference_split(_world(two_v, two_e))  # a generated shape's reference in two pieces: left out
    # a neuron's reference in two pieces, each in its own part of the mesh the cloud shows: counted
    def parts(p):  # the path's part of the surface, and the fragment's
        return (np.asarray(p)[:, 0] > 15).astype(int)

    wn = _world(two_v, two_e, parts)
    assert not reference_split(wn)
    intact2 = Made("intact", two_v, two_e)
    assert disconnected_truth(intact2, wn, origin(intact2, two_v), set(), None)["truth_disconnected"] == 0
    # the fragment's part unseen by the cloud, or both pieces in one part: left out
    assert reference_split(_world(two_v, two_e, parts, cloud=v))
    assert reference_split(_world(two_v, two_e, lambda p: np.zeros(len(p), int)))
    # a cut curve whose warning flags only the reference's own fragment: a miss
    cut = Made("broken", two_v, np.delete(two_e, 4, axis=0))
    only_fragment = np.zeros(len(two_v), bool)
    only_fragment[len(v):] = True
    t = disconnected_truth(cut, wn, origin(cut, two_v), {"disconnected"}, only_fragment)
    assert (t["truth_disconnected"], t["pieces_located"]) == (1, False)
    assert outcome({**t, "fired_disconnected": 1}, "disconnected") == "fn"


def test_a_small_task_counts_the_broken_y_found_and_the_intact_one_quiet():
    rec = run_task(Task("synthetic", "junction_y", 1200, "clean", ("intact", "broken")))
    rows = {r["kind"]: r for r in rec["rows"]}
    assert set(rows) == {"intact", "broken"}
    assert (rows["intact"]["truth_disconnected"], rows["intact"]["fired_disconnected"]) == (0, 0)
    assert (rows["broken"]["truth_disconnected"], rows["broken"]["fired_disconnected"]) == (1, 1)
    assert rows["broken"]["curve_pieces"] > rows["broken"]["reference_pieces"] == 1
    assert rows["broken"]["truth_missing_cycles"] == 0 and rows["broken"]["truth_incomplete"] == 0
    s = next(x for x in summary_rows(rec["rows"]) if x["code"] == "disconnected" and x["condition"] == "all")
    assert (s["tp"], s["fn"], s["fp"], s["tn"]) == (1, 0, 0, 1) and s["held_out"]
