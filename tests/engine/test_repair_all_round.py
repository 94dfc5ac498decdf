"""A missing region seen all round (docs/repair.md "A thick part's fill"): the share of the cloud's
cross-sections through it that is its own, on a tube whose end or whose one side is the region; and
the broken hammer's ends filled by clean axes, where the rule before (a fill's own stretch never
judged) filled the handle's end with a tangle."""

from __future__ import annotations

import numpy as np
from broken_hammer import broken_hammer_curve

import skelcore.skeleton_repair.fill as fill
from skelcore.params import Params
from skelcore.skeleton_repair import repair
from skelcore.skeleton_repair.all_round import all_round_share


def _tube(n: int = 6000, radius: float = 1.0, length: float = 20.0) -> np.ndarray:
    rng = np.random.default_rng(0)
    a, z = rng.uniform(0, 2 * np.pi, n), rng.uniform(0, length, n)
    return np.c_[radius * np.cos(a), radius * np.sin(a), z]


def test_a_tubes_end_is_seen_all_round_and_its_side_is_not():
    cloud = _tube()
    end = cloud[:, 2] > 14.0
    side = (cloud[:, 2] > 4.0) & (cloud[:, 2] < 16.0) & (cloud[:, 0] > 0.0)  # half the ring: a half of it
    assert all_round_share(cloud, end, 0.5) > 0.99
    # the cross-sections of the side hold both halves of the ring
    assert 0.4 < all_round_share(cloud, side, 0.5) < 0.6
    assert all_round_share(cloud, np.zeros(len(cloud), bool), 0.5) is None


def _tips(curve) -> int:
    deg = np.bincount(curve.edges.ravel(), minlength=curve.n_vertices)
    return int(np.count_nonzero(deg == 1))


def test_the_broken_hammers_ends_are_filled_by_clean_axes_not_a_tangle(monkeypatch):
    cloud, broken = broken_hammer_curve()
    r = repair(cloud, broken)
    after = r.log["repair"]["measures_after"]
    assert r.tally_after["missing_parts"] == 0 and after["completeness"] > 0.9
    assert after["centeredness"] > 0.8 and _tips(r.curve) <= 4
    fills = [o["why"] for o in r.log["operations"] if o["why"]["defect"] == "incomplete"]
    assert {w["region"] for w in fills} and all("centroids of its slabs" in w["reason"] for w in fills)
    assert all(w["all_round"] >= Params().repair_all_round for w in fills)
    # the order before: the axis curve of the handle's end kept, a tangle on its surface
    monkeypatch.setattr(fill, "SLABS_FIRST", False)
    old = repair(cloud, broken)
    assert old.log["repair"]["measures_after"]["centeredness"] < 0.5 and _tips(old.curve) > 20
