"""The calibration's truth for ``spurious_branches`` on a traced neuron (docs/diagnostics.md "Precision
and recall per warning", docs/benchmark.md): twigs wholly beyond the mesh by more than a traced radius
are spurious relative to the cloud, twigs within a radius of it are shown; a flag on a shown twig is a
false alarm, flags on beyond twigs alone a hit, a quiet skeleton with beyond twigs a miss."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore.benchmark.calibration.skeletons import Made, World
from skelcore.benchmark.calibration.truth import TWIG_OUT, origin, row_truth, twig_kinds
from skelcore.benchmark.neurons import load_neuron, node_facts
from skelcore.curve import CurveSkeleton
from skelcore.diagnostics.branches import decompose_branches
from skelcore.diagnostics.record import DEFECT_BITS


@pytest.fixture(scope="module")
def case():
    n = load_neuron("1734350788")  # a tuning neuron
    sk = n.skeleton
    v, e, r = sk.vertices, sk.edges, np.asarray(sk.radius, float)
    w = World(np.zeros((0, 3)), np.zeros(0), (v, e, r), lambda p: np.zeros(len(p)), True, node_facts(n))
    made = Made("intact", np.asarray(v, float), np.asarray(e, np.int64))
    curve = CurveSkeleton.from_raw(made.vertices, made.edges)
    br = decompose_branches(curve)
    deg = curve.degrees()
    out_r = np.asarray(w.facts.outside_radii)
    kinds = {}
    for b in br.terminal():
        own = [x for x in br.paths[b] if deg[x] <= 2]
        far = out_r[own] > TWIG_OUT
        kinds.setdefault("beyond" if far.all() else "partly" if far.any() else "shown", []).append(int(b))
    return w, made, br.vertex_branch, kinds


def _truth(case, flagged: list[int]):
    w, made, branch, _ = case
    flag = np.isin(branch, flagged) & (branch >= 0)
    arrays = {"curve_vertex_defects": np.where(flag, DEFECT_BITS["spurious_branches"], 0),
              "curve_vertex_branch": branch}
    fired = {"spurious_branches"} if flagged else set()
    return row_truth(made, w, "clean", fired, arrays, first=False)


def test_twigs_are_sorted_by_the_mesh(case):
    w, made, branch, kinds = case
    assert len(kinds["beyond"]) >= 20 and len(kinds["shown"]) >= 20 and len(kinds["partly"]) >= 20
    got = twig_kinds(made, origin(made, w.ref[0]), w, branch)
    for k, ids in kinds.items():
        assert all(got[b] == k for b in ids)


def test_a_flag_on_a_shown_twig_is_a_false_alarm(case):
    kinds = case[3]
    row = _truth(case, [kinds["shown"][0], kinds["beyond"][0]])
    assert row["truth_spurious_branches"] == 0 and row["flagged_shown"] == 1 and row["flagged_beyond"] == 1


def test_flags_on_beyond_twigs_are_a_hit_and_partly_beyond_decides_nothing(case):
    kinds = case[3]
    assert _truth(case, kinds["beyond"][:3])["truth_spurious_branches"] == 1
    assert _truth(case, kinds["beyond"][:1] + kinds["partly"][:2])["truth_spurious_branches"] == 1
    assert _truth(case, kinds["partly"][:2])["truth_spurious_branches"] is None


def test_a_quiet_skeleton_with_twigs_beyond_the_mesh_is_a_miss(case):
    row = _truth(case, [])
    assert row["truth_spurious_branches"] == 1 and row["twigs_beyond"] == len(case[3]["beyond"])
