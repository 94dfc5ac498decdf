"""The never-worse rule for a fill of a missing part (docs/repair.md "Fills that pass"): kept when it
explains more of the cloud and leaves less of it in counted missing parts, with no defect of another
kind more; curve centeredness is judged on the edges that were there before, so a new branch off the
tube's axis (a missing region holds only the unexplained side of a tube) does not count as a loss.
cao's curves of the neurons lost every such fill to that dilution or to a region split in two."""

from __future__ import annotations

from types import SimpleNamespace

import numpy as np

from skelcore.params import Params
from skelcore.skeleton_repair.findings import TALLIED, Findings
from skelcore.skeleton_repair.guard import kept_part, verdict


def _found(completeness: float, share: float, parts: int, c: np.ndarray, edge: np.ndarray, **more: int) -> Findings:
    tally = dict.fromkeys(TALLIED, 0)
    tally.update(missing_parts=parts, **more)
    centred = c[np.isfinite(c)]
    return Findings({"completeness": completeness, "outside_share": 0.0, "boundedness": 0.8,
                     "centeredness": float(np.mean(centred > Params().c_star))}, tally, None, [],
                    SimpleNamespace(missing_share=share), edge, np.ones(len(c)), c, np.zeros(len(c)))


def test_a_fill_is_judged_by_what_it_explains_not_by_its_own_centeredness():
    p = Params()
    # before: 10 samples on edges 0..4, 3 of them centred (c > c* = 0.75): curve centeredness 0.3
    c0 = np.array([0.9, 0.9, 0.9, 0.1, 0.1, 0.1, 0.1, 0.1, 0.1, np.nan])
    e0 = np.repeat(np.arange(5), 2)
    before = _found(0.52, 0.155, 12, c0, e0, spurious_cycles=8)
    # after: the same 10 samples, 10 more on the new edges 5..9 (none centred): 0.3 -> 0.16 for the curve
    c1, e1 = np.r_[c0, np.full(10, 0.2)], np.r_[e0, np.repeat(np.arange(5, 10), 2)]
    kept = np.arange(10) < 5
    split = _found(0.577, 0.107, 14, c1, e1, spurious_cycles=8)  # the region filled in part: two pieces left
    assert split.measures["centeredness"] < before.measures["centeredness"] - p.repair_score_drop
    assert kept_part(split.measures, e1, c1, kept, p)["centeredness"] == before.measures["centeredness"]
    assert verdict(before, split, p).startswith("worse: curve centeredness")  # the rule for other actions
    assert verdict(before, split, p, kept=kept) is None
    # refused: a cycle more; the counted share up (a piece newly counted); no completeness gained
    assert "spurious_cycles" in verdict(before, _found(0.58, 0.10, 11, c1, e1, spurious_cycles=9), p, kept=kept)
    assert verdict(before, _found(0.53, 0.165, 12, c1, e1, spurious_cycles=8), p, kept=kept).startswith("no progress")
    assert verdict(before, _found(0.52, 0.10, 11, c1, e1, spurious_cycles=8), p, kept=kept).startswith("no progress")
    # refused: the curve that was there less centred (the attachment moved its samples)
    c2 = c1.copy()
    c2[:3] = 0.1
    assert verdict(before, _found(0.58, 0.10, 11, c2, e1, spurious_cycles=8), p, kept=kept).startswith(
        "worse: curve centeredness")
