"""A twig that ends under ``spur_twig_spacings`` cloud spacings past its junction's ball (r_J) is
unresolved, not spurious (docs/diagnostics.md "Spurious branches", rule 3): the cloud gives a real
twig there no point of its own, so the explanation measure cannot tell it from a spur. Checked on the
calibration's non-uniform cloud of a tuning neuron at 30k points, where two traced twigs within a
traced radius of the mesh (shown by the cloud) were flagged before. A twig whose tip stands in the air
(farther from the cloud than its part past the ball plus ``spur_twig_tip_spacings`` spacings) is judged:
a traced twig beyond the mesh on the same cloud is flagged, where the rule without the tip's test left
it unresolved (section "A tip in the air")."""

from __future__ import annotations

import numpy as np
import pytest

from skelcore import Params
from skelcore.benchmark.calibration.skeletons import world
from skelcore.benchmark.calibration.truth import TWIG_OUT
from skelcore.benchmark.neurons import load_neuron
from skelcore.curve import CurveSkeleton
from skelcore.diagnostics import find_spurious_branches
from skelcore.diagnostics.spurs import unsampled_twig

NEURON = "1734350788"  # a tuning neuron
#: the traced nodes (SWC ids) of two twigs within a traced radius of the mesh; both fail only the
#: explanation measure at a junction of about 2 spacings and end 0.9-1.2 spacings past its ball
SHOWN_TWIGS = ((4292, 4293), (4415,))
#: a traced twig 2.1-3.3 traced radii out of the mesh (beyond the cloud), 1.0 spacing past its junction's
#: ball, its tip 5.0 spacings from the cloud
AIR_TWIG = (4024, 4025, 4026)


@pytest.fixture(scope="module")
def nonuniform():
    w = world("real", NEURON, 30_000, "nonuniform", 0)
    v, e, _ = w.ref
    at = {int(i): k for k, i in enumerate(load_neuron(NEURON).node_ids)}
    return w, CurveSkeleton.from_raw(v, e), at


def _twig(result, at, nodes) -> int:
    b = {int(result.branches.vertex_branch[at[n]]) for n in nodes}
    assert len(b) == 1
    return b.pop()


def test_shown_twigs_barely_past_the_junction_ball_are_unresolved(nonuniform):
    w, curve, at = nonuniform
    p = Params()
    new = find_spurious_branches(w.cloud, curve)
    old = find_spurious_branches(w.cloud, curve, params=Params(spur_twig_spacings=0.0))
    out_r = np.asarray(w.facts.outside_radii)
    for nodes in SHOWN_TWIGS:
        assert (out_r[[at[n] for n in nodes]] <= TWIG_OUT).all()  # the cloud shows them: a flag is a false alarm
        b = _twig(new, at, nodes)
        assert b in new.terminal and new.reach[b] > p.spur_reach
        assert new.junction_radius[b] >= p.spur_resolved_spacings * new.spacing[b]  # the junction is resolved
        assert new.unique[b] == 0  # no point of its own: the explanation measure alone fails
        past = (new.reach[b] - p.spur_reach) * new.junction_radius[b]
        assert 0 < past < p.spur_twig_spacings * new.spacing[b]
        assert new.tip_distance[b] - past < p.spur_twig_tip_spacings * new.spacing[b]  # the tip near the cloud
        assert new.unresolved[b] and not new.branch_spurious[b]
        assert old.branch_spurious[_twig(old, at, nodes)]  # flagged without the rule
    assert new.to_dict()["unresolved"] > old.to_dict()["unresolved"]
    assert len(new.spurious) < len(old.spurious)


def test_a_twig_whose_tip_stands_in_the_air_is_judged(nonuniform):
    w, curve, at = nonuniform
    p = Params()
    new = find_spurious_branches(w.cloud, curve)
    old = find_spurious_branches(w.cloud, curve, params=Params(spur_twig_tip_spacings=float("inf")))
    assert (np.asarray(w.facts.outside_radii)[[at[n] for n in AIR_TWIG]] > TWIG_OUT).all()  # beyond the cloud
    b = _twig(new, at, AIR_TWIG)
    assert new.unique[b] == 0 and new.reach[b] > p.spur_reach
    past = (new.reach[b] - p.spur_reach) * new.junction_radius[b]
    assert 0 < past < p.spur_twig_spacings * new.spacing[b]  # within the twig rule's reach ...
    assert new.tip_distance[b] - past > p.spur_twig_tip_spacings * new.spacing[b]  # ... but its tip in the air
    assert new.branch_spurious[b] and not new.unresolved[b]
    ob = _twig(old, at, AIR_TWIG)
    assert old.unresolved[ob] and not old.branch_spurious[ob]  # the rule without the tip's test spared it
    assert set(old.spurious) < set(new.spurious)


def test_the_rule_reads_the_part_past_the_junction_ball_in_spacings():
    reach = np.array([1.2, 1.6, 1.8, 3.0, np.nan])
    r_j = np.full(5, 2.0)
    s = np.ones(5)
    # past r_J: 0.4, 1.2, 1.6, 4.0 spacings; NaN is never unsampled; 0 turns the rule off
    def got(k: float, spacing: np.ndarray) -> list[bool]:
        return unsampled_twig(reach, r_j, spacing, Params(spur_twig_spacings=k)).tolist()

    assert got(1.5, s) == [True, True, False, False, False]
    assert got(1.0, s) == [True, False, False, False, False]
    assert got(1.0, 2 * s) == [True, True, True, False, False]
    assert not any(got(0.0, s))


def test_a_tip_beyond_its_part_past_the_ball_by_the_threshold_is_not_spared():
    reach = np.array([1.2, 1.2, 1.2, 1.6])
    r_j = np.full(4, 2.0)
    s = np.ones(4)
    tip = np.array([0.4, 3.6, 3.7, 10.0])  # minus the part past the ball (0.4, 0.4, 0.4, 1.2): 0, 3.2, 3.3, 8.8
    p = Params(spur_twig_spacings=1.5, spur_twig_tip_spacings=3.25)
    assert unsampled_twig(reach, r_j, s, p, tip).tolist() == [True, True, False, False]
    assert unsampled_twig(reach, r_j, s, p).tolist() == [True, True, True, True]
    assert unsampled_twig(reach, r_j, 2 * s, p, tip).tolist() == [True, True, True, False]  # 8.8 > 6.5
